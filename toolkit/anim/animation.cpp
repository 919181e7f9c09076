#include "toolkit/anim/animation.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace ptc {
namespace {

// The fallback of renumber_vertices: positions in the source's order into a buffer, then gathered.
class GatheredAnimation final : public Animation {
 public:
  GatheredAnimation(AnimationPtr inner, std::vector<std::uint32_t> to_old)
      : inner_(std::move(inner)), to_old_(std::move(to_old)), rest_(ptc::renumber_vertices(inner_->rest(), to_old_)),
        buffer_(to_old_.size()) {}
  const Mesh& rest() const override { return rest_; }
  std::size_t frame_count() const override { return inner_->frame_count(); }
  double frames_per_second() const override { return inner_->frames_per_second(); }
  void positions(double frame, std::span<Vec3> out) override {
    if (out.size() != to_old_.size())
      throw std::invalid_argument("positions: output holds " + std::to_string(out.size()) + " vertices, the source has " +
                                  std::to_string(to_old_.size()));
    inner_->positions(frame, buffer_);
    for (std::size_t i = 0; i < to_old_.size(); ++i) out[i] = buffer_[to_old_[i]];
  }
  std::string describe() const override { return inner_->describe() + " (vertices renumbered by a gather per frame)"; }
  bool is_static() const override { return inner_->is_static(); }
  bool renumber_vertices_in_place(std::span<const std::uint32_t> to_old) override {
    // Compose: new new index i is old index to_old_[to_old[i]].
    if (to_old.size() != to_old_.size())
      throw std::invalid_argument("renumber_vertices: " + std::to_string(to_old.size()) + " entries for " +
                                  std::to_string(to_old_.size()) + " vertices");
    rest_ = ptc::renumber_vertices(rest_, to_old);  // validates to_old
    std::vector<std::uint32_t> c(to_old.size());
    for (std::size_t i = 0; i < c.size(); ++i) c[i] = to_old_[to_old[i]];
    to_old_ = std::move(c);
    return true;
  }

 private:
  AnimationPtr inner_;
  std::vector<std::uint32_t> to_old_;
  Mesh rest_;
  std::vector<Vec3> buffer_;
};

}  // namespace

AnimationPtr renumber_vertices(AnimationPtr source, std::span<const std::uint32_t> to_old) {
  if (!source) throw std::invalid_argument("renumber_vertices: no source");
  if (to_old.size() != source->rest().vertex_count())
    throw std::invalid_argument("renumber_vertices: " + std::to_string(to_old.size()) + " entries for " +
                                std::to_string(source->rest().vertex_count()) + " vertices");
  check_permutation(to_old);  // before anything changes
  if (source->renumber_vertices_in_place(to_old)) return source;
  return std::make_unique<GatheredAnimation>(std::move(source), std::vector<std::uint32_t>(to_old.begin(), to_old.end()));
}

}  // namespace ptc

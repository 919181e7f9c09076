// Cloth falling onto a sphere and sliding off it onto the floor - the classic animated
// ray-tracing benchmark scene (issue 6, source 4).
//
// Model: position-based dynamics (Mueller, Heidelberger, Hennix, Ratcliff, "Position Based
// Dynamics", VRIPHYS 2006), every particle of mass 1:
//   per frame: `substeps` steps of h = 1 / (fps * substeps) seconds, each
//     v += h g;  v *= (1 - damping h);  x_pred = x + h v            (symplectic Euler predict)
//     repeat `iterations` times:
//       project every distance constraint |x_i - x_j| = L_ij  (stiffness k per kind, eq. (8)
//       of the paper with equal masses: each end moves by k (|d| - L) / 2 along d)
//       project collisions: a particle closer than r + thickness to the sphere centre is moved
//       radially to that distance; one below floor + thickness is lifted to it
//     v = (x_pred - x) / h;  x = x_pred;  friction: a particle in contact keeps (1 - friction)
//     of its tangential velocity and loses its inward normal velocity.
// Constraints on the n x n grid (spacing a = size / (n - 1)): stretch (grid edges, L = a, k =
// stretch_stiffness), shear (both quad diagonals, L = a sqrt 2, k = shear_stiffness) and
// bending (every second particle along rows and columns, L = 2a, k = bend_stiffness).
//
// Determinism: constraints are projected in a fixed order of independent colour classes (no
// two constraints of a class share a particle: e.g. horizontal edges (i, j)-(i, j+1) with j
// even, then with j odd), so a class runs in parallel (oneTBB) with no races and the result is
// bit-identical for any thread count and any run. Frames are integer simulation steps; a
// fractional time interpolates linearly between its two neighbouring frames; asking for an
// earlier time restarts from frame 0.
//
// Topology: vertex (i, j) = i n + j (row i along z, column j along x), quad (i, j) split along
// its (i, j)-(i+1, j+1) diagonal: 2 (n - 1)^2 triangles, fixed. Initial state: flat, horizontal,
// at rest, centred at (sphere centre x + offset, sphere top + drop, sphere centre z).
#pragma once

#include <cstdint>
#include <vector>

#include "toolkit/anim/animation.h"

namespace ptc {

struct ClothParams {
  int resolution = 32;           ///< n particles per side, >= 2 (2 (n-1)^2 triangles)
  double size = 2.0;             ///< side length of the square cloth (m), > 0
  Vec3 sphere_center = Vec3::Zero();
  double sphere_radius = 0.5;    ///< m, > 0
  double drop = 0.1;             ///< initial height of the cloth above the sphere top (m), >= 0
  double offset = 0.25;          ///< initial x offset of the cloth centre from the sphere centre (m);
                                 ///< off-centre so that the cloth slides off instead of draping
  bool floor = true;             ///< a floor plane y = sphere_center.y - sphere_radius
  double gravity = 9.81;         ///< m/s^2 along -y, >= 0
  double fps = 30.0;             ///< frames per second, > 0
  int substeps = 8;              ///< time steps per frame, 1..1000
  int iterations = 4;            ///< constraint passes per substep, 1..1000
  double stretch_stiffness = 1.0;  ///< in [0, 1]
  double shear_stiffness = 0.5;    ///< in [0, 1]
  double bend_stiffness = 0.1;     ///< in [0, 1]
  double damping = 0.2;          ///< velocity damping rate (1/s), >= 0
  double friction = 0.1;         ///< tangential velocity lost per contact step, in [0, 1]
  double thickness = 0.0;        ///< collision offset (m), >= 0; 0 = size / (n - 1) / 4
};

/// "" or the reason the parameters are invalid.
[[nodiscard]] std::string check(const ClothParams& p);

class ClothSimulation final : public Animation {
 public:
  /// InputError (element "cloth", reason from check()) for bad parameters.
  explicit ClothSimulation(const ClothParams& params);

  /// The flat initial grid (frame 0).
  [[nodiscard]] const Mesh& rest() const override { return rest_; }
  [[nodiscard]] std::size_t frame_count() const override { return 0; }
  [[nodiscard]] double frames_per_second() const override { return p_.fps; }
  /// Simulates up to ceil(frame) (restarting when frame is before the current state), then
  /// writes the state (or the linear blend of frames floor and ceil). std::invalid_argument
  /// for a negative or non-finite time or a wrong out size. No allocation after construction.
  void positions(double frame, std::span<Vec3> out) override;
  [[nodiscard]] std::string describe() const override;

  [[nodiscard]] const ClothParams& params() const { return p_; }
  /// Frames simulated so far (the state is frame `frame()`).
  [[nodiscard]] std::int64_t frame() const { return frame_; }
  /// Current particle positions and velocities (m/s).
  [[nodiscard]] std::span<const Vec3> state_positions() const { return x_; }
  [[nodiscard]] std::span<const Vec3> state_velocities() const { return v_; }
  /// Kinetic + gravitational energy per unit particle mass, potential measured from the floor
  /// height (sphere_center.y - sphere_radius): sum 1/2 |v|^2 + g (y - floor).
  [[nodiscard]] double energy() const;
  /// Collision radius (sphere_radius + thickness) and thickness actually used.
  [[nodiscard]] double collision_radius() const { return p_.sphere_radius + thickness_; }
  [[nodiscard]] double thickness() const { return thickness_; }
  /// Restart from the initial state (frame 0).
  void reset();
  /// Advance the state by one frame.
  void step_frame();

 private:
  struct Constraint {
    std::uint32_t i, j;
    double rest;
  };
  struct Group {  // an independent colour class: no two constraints share a particle
    std::size_t begin, end;
    double stiffness;
  };
  void substep(double h);
  void project_collisions(std::size_t begin, std::size_t end);

  ClothParams p_;
  double thickness_ = 0;
  Mesh rest_;
  std::vector<Vec3> x_, v_, pred_, prev_frame_;
  std::vector<Constraint> constraints_;
  std::vector<Group> groups_;
  std::int64_t frame_ = 0;
};

}  // namespace ptc

// VTK pictures checked pixel by pixel against an independent answer: the closest triangle of
// every pixel's primary ray by brute force (tests/common/brute_force.h), with the camera of
// `ptc trace`. Pixels whose 3x3 neighbourhood sees one triangle must show exactly that
// triangle's colour (unlit) or a multiple of it (lit); the orientation, the camera conventions
// and the pixel centres are all in that check. Every test starts its own Xvfb.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <set>

#include "common/brute_force.h"
#include "render/camera.h"
#include "toolkit/core/error.h"
#include "viz/colour_scale.h"
#include "viz/display.h"
#include "viz/legend.h"
#include "viz/partition_colours.h"
#include "viz/renderer.h"

namespace ptc::viz {
namespace {

// An n x n grid of quads (2 triangles each) in the plane z = 0, bent a little so that the lit
// picture has different shades, spanning [0, n] x [0, n].
Mesh grid(int n, double bend = 0.0) {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) p.emplace_back(x, y, bend * (x - n / 2.0) * (x - n / 2.0));
  const auto id = [n](int x, int y) { return static_cast<std::uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      t.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      t.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  return Mesh(std::move(t), std::move(p));
}

Rgb8 id_colour(std::uint32_t t) {  // distinct, never the background
  return {static_cast<std::uint8_t>(40 + (t * 53) % 200), static_cast<std::uint8_t>(10 + (t * 97) % 240),
          static_cast<std::uint8_t>(200 - (t * 31) % 150)};
}

constexpr std::uint32_t kMiss = 0xffffffffu;

// Closest triangle per pixel (kMiss for a miss), row-major from the top-left.
std::vector<std::uint32_t> brute_ids(const Mesh& m, const bvh::PinholeCamera& cam, int w, int h) {
  const bvh::RayBatch rays = camera_rays(cam, w, h);
  std::vector<std::uint32_t> ids(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const bvh::Hit hit = bvh::test::brute_force(m, Vec3::Zero(), Vec3(rays.ox[i], rays.oy[i], rays.oz[i]),
                                                     bvh::Vec3f{rays.dx[i], rays.dy[i], rays.dz[i]});
    ids[i] = hit.hit() ? hit.triangle : kMiss;
  }
  return ids;
}

bool interior(const std::vector<std::uint32_t>& ids, int w, int h, int x, int y) {
  if (x < 1 || y < 1 || x >= w - 1 || y >= h - 1) return false;
  const std::uint32_t c = ids[static_cast<std::size_t>(y) * w + x];
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (ids[static_cast<std::size_t>(y + dy) * w + x + dx] != c) return false;
  return true;
}

TEST(Display, StartsItsOwnXvfbAndStopsIt) {
  const char* before = std::getenv("DISPLAY");
  const std::string saved = before ? before : "";
  pid_t pid = 0;
  {
    Display::Options o;
    o.force_xvfb = true;
    Display d = Display::acquire(o);
    ASSERT_TRUE(d.own_server());
    pid = d.server_pid();
    EXPECT_GT(pid, 0);
    EXPECT_EQ(std::string(std::getenv("DISPLAY")), d.name());
    EXPECT_TRUE(display_usable(d.name()));
    EXPECT_EQ(kill(pid, 0), 0) << "the server runs while the Display lives";
    EXPECT_EQ(getpgid(pid), pid) << "its own process group: a terminal's Ctrl-C is not sent to it";
  }
  EXPECT_NE(kill(pid, 0), 0) << "the server is gone (and reaped) after the Display";
  const char* after = std::getenv("DISPLAY");
  EXPECT_EQ(after ? std::string(after) : std::string(), saved);
}

TEST(Display, MissingXvfbIsOneLineSayingWhatToInstall) {
  const char* before = std::getenv("DISPLAY");
  const std::string saved = before ? before : "";
  unsetenv("DISPLAY");
  Display::Options o;
  o.xvfb = "ptc-no-such-xvfb-program";
  try {
    (void)Display::acquire(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("no X display is reachable"), std::string::npos) << w;
    EXPECT_NE(w.find("apt-get install --no-install-recommends xvfb"), std::string::npos) << w;
    EXPECT_EQ(w.find('\n'), std::string::npos) << w;
  }
  o.interactive = true;
  try {
    (void)Display::acquire(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--interactive needs a display"), std::string::npos) << e.what();
  }
  if (!saved.empty()) setenv("DISPLAY", saved.c_str(), 1);
}

TEST(Display, AServerThatFailsIsReportedWithItsMessage) {
  Display::Options o;
  o.force_xvfb = true;
  o.xvfb = "/bin/false";
  try {
    (void)Display::acquire(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Xvfb did not start"), std::string::npos) << e.what();
  }
}

TEST(Display, AUserDisplayWithoutAUsableGlContextFallsBackToXvfb) {
  // A working display, then the same display as ssh -X would give it (indirect GLX, which Mesa
  // refuses for OpenGL 3.2): VTK would abort there; the probe sees it and a private Xvfb is used.
  Display::Options o;
  o.force_xvfb = true;
  Display user = Display::acquire(o);
  EXPECT_EQ(gl_problem(user.name()), "");
  setenv("LIBGL_ALWAYS_INDIRECT", "1", 1);
  EXPECT_NE(gl_problem(user.name()), "");
  {
    Display d = Display::acquire();  // $DISPLAY is the user's, which fails the probe
    EXPECT_TRUE(d.own_server());
    EXPECT_NE(d.name(), user.name());
    EXPECT_NE(d.describe().find("the user's display"), std::string::npos) << d.describe();
    EXPECT_EQ(std::getenv("LIBGL_ALWAYS_INDIRECT"), nullptr) << "not inherited by the private server's clients";
    Renderer r(d);
    const Mesh m = grid(2);
    MeshStyle st;
    st.triangle_colours.assign(m.triangle_count(), Rgb8{200, 10, 10});
    st.lighting = false;
    const RgbImage img = r.mesh(m, st, make_camera({}, m.bounds(), 16, 16), 16, 16);
    EXPECT_EQ(img.at(8, 8), (Rgb8{200, 10, 10}));
  }
  EXPECT_STREQ(std::getenv("LIBGL_ALWAYS_INDIRECT"), "1") << "restored";
  EXPECT_EQ(std::string(std::getenv("DISPLAY")), user.name());
  Display::Options i;
  i.interactive = true;
  EXPECT_THROW((void)Display::acquire(i), InputError) << "a window on a display that cannot render: refused";
  i.force_xvfb = true;
  EXPECT_THROW((void)Display::acquire(i), UsageError) << "--interactive with --xvfb";
  unsetenv("LIBGL_ALWAYS_INDIRECT");
}

class RendererTest : public ::testing::Test {
 protected:
  static Display::Options xvfb() {
    Display::Options o;
    o.force_xvfb = true;
    return o;
  }
  Display display_ = Display::acquire(xvfb());
  Renderer renderer_{display_};
};

TEST_F(RendererTest, UnlitPixelsAreTheColourOfTheTriangleTheTracerHits) {
  const Mesh m = grid(6);
  const int w = 120, h = 90;
  CameraSpec spec;
  spec.eye = Vec3(-0.5, 1.0, 5.5);  // oblique, so the perspective and the up vector matter
  spec.look_at = Vec3(3.0, 3.2, 0.0);
  spec.up = Vec3(0.2, 1.0, 0.0);
  spec.fov_deg = 50;
  const bvh::PinholeCamera cam = make_camera(spec, m.bounds(), w, h);
  MeshStyle st;
  st.lighting = false;
  for (std::uint32_t t = 0; t < m.triangle_count(); ++t) st.triangle_colours.push_back(id_colour(t));
  const RgbImage img = renderer_.mesh(m, st, cam, w, h);
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.height, h);
  const auto ids = brute_ids(m, cam, w, h);
  int checked = 0, hit_pixels = 0, miss_pixels = 0;
  std::set<std::uint32_t> seen;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!interior(ids, w, h, x, y)) continue;
      const std::uint32_t t = ids[static_cast<std::size_t>(y) * w + x];
      const Rgb8 want = t == kMiss ? kBackground : id_colour(t);
      EXPECT_EQ(img.at(x, y), want) << "pixel (" << x << ", " << y << ") triangle " << t;
      ++checked;
      (t == kMiss ? miss_pixels : hit_pixels)++;
      if (t != kMiss) seen.insert(t);
    }
  EXPECT_GT(hit_pixels, 2000);
  EXPECT_GT(miss_pixels, 500);
  EXPECT_GT(seen.size(), 40u) << "most triangles are checked somewhere";
  EXPECT_GT(checked, w * h / 2);
}

TEST_F(RendererTest, LitPixelsKeepTheirTriangleHueAndBordersAreDrawn) {
  const Mesh m = grid(4, 0.15);
  const int w = 64, h = 64;
  CameraSpec spec;
  spec.eye = Vec3(2.0, 2.0, 6.0);
  const bvh::PinholeCamera cam = make_camera(spec, m.bounds(), w, h);
  MeshStyle st;
  for (std::uint32_t t = 0; t < m.triangle_count(); ++t) st.triangle_colours.push_back(palette_colour(t % 12));
  const RgbImage img = renderer_.mesh(m, st, cam, w, h);
  const auto ids = brute_ids(m, cam, w, h);
  int checked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!interior(ids, w, h, x, y)) continue;
      const std::uint32_t t = ids[static_cast<std::size_t>(y) * w + x];
      if (t == kMiss) continue;
      // Lambert without specular: pixel = k * colour with one k for the three channels.
      const Rgb8 c = palette_colour(t % 12), p = img.at(x, y);
      const double k = (p[0] + p[1] + p[2]) / double(c[0] + c[1] + c[2]);
      EXPECT_GT(k, 0.3);
      EXPECT_LE(k, 1.02);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(p[i], k * c[i], 4.0) << "pixel (" << x << ", " << y << ") channel " << i;
      ++checked;
    }
  EXPECT_GT(checked, 800);

  // Black border lines along the grid's middle column line x = 2: pixels on it turn dark.
  MeshStyle lined = st;
  for (int y = 0; y < 4; ++y) lined.lines.push_back({static_cast<std::uint32_t>(y * 5 + 2), static_cast<std::uint32_t>((y + 1) * 5 + 2)});
  lined.line_width = 2.0f;
  const RgbImage with_lines = renderer_.mesh(m, lined, cam, w, h);
  int darkened = 0, changed_elsewhere = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Rgb8 a = img.at(x, y), b = with_lines.at(x, y);
      const bool dark = b[0] + b[1] + b[2] < 30 && a[0] + a[1] + a[2] > 90;
      darkened += dark;
      // The camera looks straight at x = 2 (the centre), so the line is the middle column.
      if (a != b && std::abs(x - w / 2) > 4) ++changed_elsewhere;
    }
  EXPECT_GT(darkened, 30);
  EXPECT_EQ(changed_elsewhere, 0);
}

// VTK draws a mesh of 1e-30 or 1e20 units as it draws the same mesh at unit size: the renderer
// centres and scales mesh and camera first (by a power of two). Before, the small one drew an empty
// picture and the large one a nearly black one. The pictures must be the same pixel for pixel.
TEST_F(RendererTest, TinyAndHugeMeshesDrawAsAtUnitSize) {
  const Mesh m = grid(4, 0.15);
  const int w = 48, h = 48;
  CameraSpec spec;
  spec.eye = Vec3(2.0, 2.0, 6.0);
  MeshStyle st;
  for (std::uint32_t t = 0; t < m.triangle_count(); ++t) st.triangle_colours.push_back(palette_colour(t % 12));
  st.lines.push_back({2, 7});
  const RgbImage want = renderer_.mesh(m, st, make_camera(spec, m.bounds(), w, h), w, h);
  int drawn = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) drawn += want.at(x, y) != kBackground;
  ASSERT_GT(drawn, 500);
  for (const int e : {-100, -33, 66}) {
    const double s = std::ldexp(1.0, e);
    std::vector<Vec3> pos(m.positions().begin(), m.positions().end());
    for (Vec3& p : pos) p *= s;
    const Mesh ms = m.with_positions(pos);
    CameraSpec ss = spec;
    ss.eye = *spec.eye * s;
    const RgbImage got = renderer_.mesh(ms, st, make_camera(ss, ms.bounds(), w, h), w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) ASSERT_EQ(got.at(x, y), want.at(x, y)) << "2^" << e << " pixel (" << x << ", " << y << ")";
  }
}

TEST_F(RendererTest, TextStripsHaveTextWhereTheItemsAreAndNothingElse) {
  TextItem a{"frame 12", 40, 20, 16, -1};
  TextItem b{"0.125", 150, 20, 16, 1};
  const std::vector<TextItem> items{a, b};
  const RgbImage img = renderer_.text(200, 40, items);
  int lit_left = 0, lit_right = 0, lit_middle = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 200; ++x) {
      const Rgb8 p = img.at(x, y);
      if (p == kBackground) continue;
      if (x >= 38 && x < 130) ++lit_left;
      if (x >= 95 && x <= 152) ++lit_right;
      if (x < 36 || x > 154 || y < 8 || y > 32) ++lit_middle;
    }
  EXPECT_GT(lit_left, 40);
  EXPECT_GT(lit_right, 20);
  EXPECT_EQ(lit_middle, 0) << "no ink outside the two items";
}

// A legend's note that does not fit its width goes on further lines (the strip 14 pixels taller
// each) instead of running off the picture's edge (found by a new user: "548 pixels above the"
// ended at the edge of a 480-pixel heatmap).
TEST_F(RendererTest, ALegendsLongNoteWrapsInsteadOfBeingClipped) {
  const ColourScale s = make_scale("nodes_visited", std::vector<double>{}, false, 0, std::pair{2.0, 4.0});
  const LegendLayout l = legend_layout(240);
  const RgbImage short_note = legend_strip(renderer_, s, 240, "3 pixels above");
  EXPECT_EQ(short_note.height, l.height);
  const std::string long_note =
      "27310 pixels below the range drawn at the bottom colour; 548 pixels above the range drawn at the top colour";
  for (const int width : {240, 480}) {
    const RgbImage img = legend_strip(renderer_, s, width, long_note);
    const int lines = 1 + (img.height - l.height) / 14;
    EXPECT_EQ((img.height - l.height) % 14, 0) << width;
    EXPECT_GE(lines, width == 240 ? 3 : 2) << width;
    int edge_ink = 0;
    std::vector<int> ink_per_line(lines, 0);
    for (int y = 62; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        if (img.at(x, y) == kBackground) continue;
        if (x >= img.width - 3) ++edge_ink;
        ++ink_per_line[std::min(lines - 1, (y - 62) / 14)];
      }
    EXPECT_EQ(edge_ink, 0) << "no text runs to the right edge at width " << width;
    for (int i = 0; i < lines; ++i) EXPECT_GT(ink_per_line[i], 20) << "line " << i << " at width " << width;
  }
}

TEST_F(RendererTest, SizesAndColourCountsAreChecked) {
  const Mesh m = grid(1);
  MeshStyle st;
  st.triangle_colours = {Rgb8{1, 2, 3}};
  const bvh::PinholeCamera cam = make_camera({}, m.bounds(), 8, 8);
  EXPECT_THROW((void)renderer_.mesh(m, st, cam, 8, 8), std::invalid_argument);
  st.triangle_colours.push_back(Rgb8{4, 5, 6});
  EXPECT_THROW((void)renderer_.mesh(m, st, cam, 0, 8), std::invalid_argument);
  EXPECT_THROW((void)renderer_.mesh(m, st, cam, 8, 9000), std::invalid_argument);
  const RgbImage one = renderer_.mesh(m, st, cam, 1, 1);
  EXPECT_EQ(one.pixel_count(), 1u);
}

}  // namespace
}  // namespace ptc::viz

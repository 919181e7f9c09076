// The one "flag > scene > default" rule for the camera and the light (commands/scene_args.h).
#include <gtest/gtest.h>

#include <cmath>

#include "commands/scene_args.h"
#include "toolkit/core/error.h"
#include "render/view.h"
#include "toolkit/anim/static_source.h"

namespace ptc {
namespace {

Scene ball(std::optional<SceneCamera> camera, std::optional<SceneLight> light) {
  std::vector<ScenePart> parts;
  parts.push_back({"ball", std::make_unique<StaticSource>(make_sphere_mesh(Vec3::Zero(), 1.0, 1), "ball")});
  return Scene("ball", std::move(parts), camera, light);
}

TEST(SceneArgs, CameraFlagsThenTheScenesOwnThenFraming) {
  const SceneCamera own{Vec3(0, 0, 7), Vec3(0, 0.5, 0), Vec3(0, 1, 0), 30.0};
  const Scene with = ball(own, std::nullopt), without = ball(std::nullopt, std::nullopt);
  EXPECT_TRUE(with.has_own_camera());
  EXPECT_FALSE(with.has_own_light());
  EXPECT_FALSE(without.has_own_camera());
  // No flags: the scene's own camera, field by field; without one, nothing (make_camera frames).
  CameraSpec s = camera_for({}, with);
  EXPECT_EQ(*s.eye, own.eye);
  EXPECT_EQ(*s.look_at, own.look_at);
  EXPECT_EQ(*s.fov_deg, 30.0);
  s = camera_for({}, without);
  EXPECT_FALSE(s.eye || s.look_at || s.up || s.fov_deg);
  // A flag wins over the scene, field by field.
  CameraSpec flags;
  flags.eye = Vec3(3, 0, 0);
  s = camera_for(flags, with);
  EXPECT_EQ(*s.eye, Vec3(3, 0, 0));
  EXPECT_EQ(*s.look_at, own.look_at);
  // Built-in scenes have their view as their own.
  EXPECT_TRUE(make_builtin_scene("cloth-sphere-32").has_own_camera());
  EXPECT_TRUE(make_builtin_scene("cloth-sphere-32").has_own_light());
}

TEST(SceneArgs, LightFlagThenTheScenesOwnThenDefault) {
  const Scene with = ball(std::nullopt, SceneLight{Vec3(1, 9, 1), 1.0}), without = ball(std::nullopt, std::nullopt);
  const Box3 b = without.rest().bounds();
  const bvh::PinholeCamera cam = make_camera({}, b, 16, 16);
  LightChoice l = light_for(Vec3(5, 5, 5), with, cam, b, "s.json");
  EXPECT_EQ(l.position, Vec3(5, 5, 5));
  EXPECT_STREQ(l.from, "--light");
  l = light_for(std::nullopt, with, cam, b, "s.json");
  EXPECT_EQ(l.position, Vec3(1, 9, 1));
  EXPECT_STREQ(l.from, "scene");
  l = light_for(std::nullopt, without, cam, b, "s.json");
  EXPECT_EQ(l.position, default_light(cam, b));
  EXPECT_STREQ(l.from, "default");
}

// The tracer's reach (kTraceReach of the scene's trace frame from its rest centre): an eye beyond
// it is refused, a flag's as a usage error naming the flag, a scene's as bad input naming the file
// and its camera; at the bound, accepted. A light is no ray origin: a far one is taken (shadow rays
// leave the surface), one whose difference to the scene overflows is refused. The ball has radius
// 1 about (0, 0, 0): its frame's scale is 1, so the reach is 1e18 units.
TEST(SceneArgs, AnEyeBeyondTheTracersReachIsRefusedAFarLightIsNot) {
  const Scene far_light = ball(std::nullopt, SceneLight{Vec3(0, 0, 1e308), 1.0}), plain = ball(std::nullopt, std::nullopt);
  const Box3 b = plain.rest().bounds();
  const bvh::PinholeCamera cam = make_camera({}, b, 16, 16);
  EXPECT_NO_THROW((void)light_for(Vec3(1e308, 1e308, 1e308), plain, cam, b, "s.json"));
  EXPECT_NO_THROW((void)light_for(std::nullopt, far_light, cam, b, "s.json"));
  // A ball about x = 1e308 and a light at x = -1e308: their difference is beyond double.
  std::vector<ScenePart> parts;
  parts.push_back({"edge", std::make_unique<StaticSource>(make_sphere_mesh(Vec3(1e308, 0, 0), 1.0, 1), "edge")});
  const Scene edge("edge", std::move(parts), std::nullopt, SceneLight{Vec3(-1e308, 0, 0), 1.0});
  try {
    (void)light_for(Vec3(-1e308, 0, 0), edge, cam, b, "s.json");
    ADD_FAILURE() << "a light whose difference to the scene overflows was taken";
  } catch (const UsageError& e) {
    EXPECT_EQ(e.element(), "--light");
    EXPECT_NE(e.reason().find("too far apart"), std::string::npos) << e.what();
  }
  try {
    (void)light_for(std::nullopt, edge, cam, b, "s.json");
    ADD_FAILURE() << "the scene's overflowing light was taken";
  } catch (const UsageError&) {
    ADD_FAILURE() << "the scene's light was refused as a flag";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "s.json");
    EXPECT_EQ(e.element(), "light");
  }
  // The reach scales with the mesh: a ball of radius 2^-40 reaches 2^40 times less far.
  const Vec3 c = plain.rest().bounds().center();
  EXPECT_NO_THROW(check_reach(plain, Vec3(c.x(), c.y(), c.z() + 1e18), "the eye", "--eye", "--eye", "camera", "s.json"));
  EXPECT_THROW(check_reach(plain, Vec3(c.x(), c.y(), c.z() + 2e18), "the eye", "--eye", "--eye", "camera", "s.json"),
               UsageError);
  std::vector<ScenePart> tparts;
  tparts.push_back({"tiny", std::make_unique<StaticSource>(make_sphere_mesh(Vec3::Zero(), std::ldexp(1.0, -40), 1), "tiny")});
  const Scene tiny("tiny", std::move(tparts), std::nullopt, std::nullopt);
  EXPECT_THROW(check_reach(tiny, Vec3(0, 0, 1e9), "the eye", "--eye", "--eye", "camera", "s.json"), UsageError);
  EXPECT_NO_THROW(check_reach(tiny, Vec3(0, 0, 1e5), "the eye", "--eye", "--eye", "camera", "s.json"));
  // The eye: from --eye a usage error, from the scene's camera bad input, from a framing moved
  // by --fov that flag.
  bvh::PinholeCamera far = cam;
  far.eye = Vec3(0, 0, -3e18);
  CameraSpec flags;
  flags.eye = far.eye;
  EXPECT_THROW(check_eye_reach(far, flags, plain, "s.json"), UsageError);
  try {
    check_eye_reach(far, CameraSpec{}, ball(SceneCamera{}, std::nullopt), "s.json");
    ADD_FAILURE() << "the scene's eye at 3e18 was taken";
  } catch (const UsageError&) {
    ADD_FAILURE() << "the scene's eye was refused as a flag";
  } catch (const InputError& e) {
    EXPECT_EQ(e.element(), "camera");
  }
  CameraSpec fov;
  fov.fov_deg = 1e-30;
  try {
    check_eye_reach(far, fov, plain, "s.json");
    ADD_FAILURE() << "the framing eye at 3e18 was taken";
  } catch (const UsageError& e) {
    EXPECT_EQ(e.element(), "--fov");
  }
  EXPECT_NO_THROW(check_eye_reach(cam, CameraSpec{}, plain, "s.json"));
}

}  // namespace
}  // namespace ptc

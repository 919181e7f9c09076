// The one "flag > scene > default" rule for the camera and the light (commands/scene_args.h).
#include <gtest/gtest.h>

#include "commands/scene_args.h"
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
  LightChoice l = light_for(Vec3(5, 5, 5), with, cam, b);
  EXPECT_EQ(l.position, Vec3(5, 5, 5));
  EXPECT_STREQ(l.from, "--light");
  l = light_for(std::nullopt, with, cam, b);
  EXPECT_EQ(l.position, Vec3(1, 9, 1));
  EXPECT_STREQ(l.from, "scene");
  l = light_for(std::nullopt, without, cam, b);
  EXPECT_EQ(l.position, default_light(cam, b));
  EXPECT_STREQ(l.from, "default");
}

}  // namespace
}  // namespace ptc

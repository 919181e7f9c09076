// The shared argument parsers: frames ("F", "A:B"), vectors ("X,Y,Z"), the frame-range check.
#include <gtest/gtest.h>

#include "commands/args.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/scene.h"
#include "toolkit/core/error.h"

namespace ptc {
namespace {

std::string element_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.element();
  }
  return "(no error)";
}

TEST(Args, ParseVec3) {
  std::string why;
  EXPECT_EQ(*parse_vec3("1,2,3"), Vec3(1, 2, 3));
  EXPECT_EQ(*parse_vec3(" -1.5e2 , +0 ,4 "), Vec3(-150, 0, 4));
  for (const char* bad : {"", "1,2", "1,2,3,4", "1,,3", "a,b,c", "1;2;3", "1,2,3x", "nan,0,0", "0,inf,0",
                          "1e999,0,0", "--1,0,0", ",1,2"}) {
    EXPECT_FALSE(parse_vec3(bad, &why)) << bad;
    EXPECT_FALSE(why.empty()) << bad;
  }
}

TEST(Args, FramesAndRangesHaveOneMeaning) {
  EXPECT_EQ(parse_frame("0", "--frame"), 0);
  EXPECT_EQ(parse_frame("17", "--frame"), 17);
  const FrameRange one = parse_frame_range("4", "--frames");
  EXPECT_EQ(one.first, 4);
  EXPECT_EQ(one.last, 4);
  const FrameRange r = parse_frame_range("2:9", "--frames");
  EXPECT_EQ(r.first, 2);
  EXPECT_EQ(r.last, 9);
  EXPECT_EQ(r.count(), 8);
  for (const char* bad : {"", "-1", "a", "1:", ":3", "1:2:3", "5:2", "1.5", " 3", "3 ", "1..4", "99999999999999999999"})
    EXPECT_EQ(element_of([&] { (void)parse_frame_range(bad, "--frames"); }), "--frames") << bad;
  for (const char* bad : {"", "-1", "x", "2:3"})
    EXPECT_EQ(element_of([&] { (void)parse_frame(bad, "--frame"); }), "--frame") << bad;
}

TEST(Args, FramesOutsideTheScenesRangeNeedExtendFrames) {
  std::vector<ScenePart> parts;
  parts.push_back({"ball", make_deformer(make_sphere_mesh(Vec3::Zero(), 1.0, 1), deform_preset(DeformKind::Twist))});
  const Scene s("ball", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, 59});
  EXPECT_NO_THROW(check_frames(s, {0, 59}, "ball", "--frames", false));
  EXPECT_NO_THROW(check_frames(s, {10, 10}, "ball", "--frame", false));
  EXPECT_EQ(element_of([&] { check_frames(s, {0, 60}, "ball", "--frames", false); }), "--frames");
  EXPECT_EQ(element_of([&] { check_frames(s, {500, 500}, "ball", "--frame", false); }), "--frame");
  EXPECT_NO_THROW(check_frames(s, {0, 1000}, "ball", "--frames", true));  // a deformer goes on for ever
}

}  // namespace
}  // namespace ptc

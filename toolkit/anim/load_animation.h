// One front door from a path to an animation source (issue 6: "wherever a command takes a SCENE
// it accepts ... a mesh or animated asset file, or a directory of frame files").
//
//   directory or glob (* ? [)       -> FrameSequence (frame_sequence.h)
//   .md2                            -> MD2 keyframes through assimp (assimp_source.h)
//   .md3                            -> MD3 keyframes, own reader (md3.h)
//   .obj .ply .off .stl             -> StaticSource of the mesh (toolkit/io)
//   anything else                   -> assimp: skinned / node-animated asset, or a StaticSource
//                                      when the file has no animation
// Errors are InputErrors naming the path.
#pragma once

#include <string>

#include "toolkit/anim/animation.h"
#include "toolkit/anim/assimp_source.h"
#include "toolkit/anim/frame_sequence.h"
#include "toolkit/anim/md3.h"

namespace ptc {

struct LoadAnimationOptions {
  FrameSequenceOptions sequence;  ///< directories and globs
  Md2Options md2;
  Md3Options md3;
  AssimpSkinOptions assimp;       ///< every other asset assimp reads
};

/// What load_animation() would make of a path, without loading it.
enum class AnimationFileKind { FrameSequence, Md2, Md3, MeshFile, AssimpAsset };
[[nodiscard]] AnimationFileKind classify_animation_path(const std::string& path);
[[nodiscard]] const char* to_string(AnimationFileKind k);

[[nodiscard]] AnimationPtr load_animation(const std::string& path, const LoadAnimationOptions& opt = {});

}  // namespace ptc

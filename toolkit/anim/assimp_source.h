// Animation sources loaded through assimp (Debian libassimp-dev); assimp itself is included only
// in assimp_source.cpp.
//
// - MD2 (Quake II vertex keyframes): assimp imports one frame per import, chosen by
//   AI_CONFIG_IMPORT_GLOBAL_KEYFRAME; we import every frame from the bytes in memory, take the
//   triangle soup assimp produces (three own vertices per face) and weld the vertices that
//   coincide in every frame. The header and triangle indices are checked by us first (assimp
//   silently clamps out-of-range vertex indices). Positions are in assimp's world: assimp 5.2 keeps
//   the file's axes in the mesh and rotates the scene by its root node, (x, y, z) -> (x, z, -y),
//   which we apply (the same axes as md3.h's default); assimp also reverses each face's corners.
// - Skeletal assets (any format assimp reads with bones and node animation: .x .dae .fbx .gltf
//   .glb .smd .ms3d ...): every mesh of every node instance is concatenated into one mesh (the
//   node tree's order, meshes in node order); bones, weights and node channels become a SkinRig
//   (skinning.h). Positions are in the scene root's space (the root node's transform included).
//   A file without animation (or whose chosen animation has no node channels) gives a static
//   source with the posed rest positions.
#pragma once

#include <filesystem>
#include <string>

#include "toolkit/anim/animation.h"
#include "toolkit/anim/skinning.h"

struct aiScene;  // assimp's scene (assimp/scene.h), only referenced here

namespace ptc {

struct Md2Options {
  bool weld = true;    ///< weld the soup (connectivity for clustering); false keeps 3 vertices per face
  double fps = 10.0;   ///< MD2 stores no rate; Quake II animates at its 10 Hz server tick
};

/// Every frame of an MD2 file as a keyframe animation. InputError for a missing, truncated or
/// malformed file (naming the byte offset and field) or an assimp import failure.
[[nodiscard]] AnimationPtr load_md2(const std::filesystem::path& path, const Md2Options& opt = {});

/// Number of frames in an MD2 file's header (InputError as above).
[[nodiscard]] std::size_t md2_frame_count(const std::filesystem::path& path);

struct AssimpSkinOptions {
  SkinOptions skin;             ///< sampling rate and welding
  unsigned animation = 0;       ///< which aiAnimation to play (InputError when out of range and the file has some)
};

/// A skinned or rigidly animated asset (see above). InputError naming the file for a missing
/// file, an import failure, a scene without triangles, or bad bone data (non-finite weights,
/// bone names that match no node).
[[nodiscard]] AnimationPtr load_assimp_animation(const std::filesystem::path& path,
                                                 const AssimpSkinOptions& opt = {});

/// The rig of an already imported scene (`name` stands for the file in errors); the building
/// block of load_assimp_animation, usable with a scene built in memory.
[[nodiscard]] SkinRig skin_rig_from_scene(const aiScene& scene, unsigned animation, const std::string& name);

}  // namespace ptc

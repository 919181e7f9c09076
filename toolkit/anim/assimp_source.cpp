#include "toolkit/anim/assimp_source.h"
#include "toolkit/core/cancel.h"

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include <fmt/format.h>

#include "toolkit/anim/frame_sequence.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/anim/weld.h"
#include "toolkit/core/error.h"
#include "toolkit/core/input_log.h"

namespace {
// Model only what a scene needs: positions, faces, bones and animation channels. Everything
// else an asset carries is dropped by assimp's RemoveComponent step right after import.
constexpr int kUnusedComponents = aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_COLORS |
                                  aiComponent_TEXCOORDS | aiComponent_TEXTURES | aiComponent_LIGHTS |
                                  aiComponent_CAMERAS | aiComponent_MATERIALS;
}  // namespace

namespace ptc {

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& path) {
  note_input_file(path);
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path.string(), "", "", "no such file");
  if (fs::is_directory(path, ec)) throw InputError(path.string(), "", "", "is a directory, not a file");
  const BlockingWaitFor waiting(path);  // (a FIFO: a stop request ends the run at once meanwhile)
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "", "", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path.string(), "", "", "read error");
  return ss.str();
}

std::uint32_t le32(const std::string& b, std::size_t off) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b[off + static_cast<unsigned>(i)]);
  return v;
}

// The MD2 header fields we rely on, checked against the file (assimp clamps bad vertex indices
// silently and reads frames by the header's frame size).
struct Md2Header {
  std::uint32_t num_xyz = 0, num_tris = 0, num_frames = 0, ofs_tris = 0, ofs_frames = 0, frame_size = 0;
};

Md2Header check_md2(const std::string& b, const std::string& name) {
  constexpr std::size_t kHeader = 68;
  if (b.size() < kHeader)
    throw InputError(name, byte_loc(b.size()), "header",
                     fmt::format("truncated: {} bytes, an MD2 header needs {}", b.size(), kHeader));
  if (b.compare(0, 4, "IDP2") != 0) throw InputError(name, byte_loc(0), "header ident", "not an MD2 file (magic is not IDP2)");
  if (le32(b, 4) != 8) throw InputError(name, byte_loc(4), "header version", fmt::format("version {} (expected 8)", le32(b, 4)));
  Md2Header h;
  h.frame_size = le32(b, 16);
  h.num_xyz = le32(b, 24);
  h.num_tris = le32(b, 32);
  h.num_frames = le32(b, 40);
  h.ofs_tris = le32(b, 52);
  h.ofs_frames = le32(b, 56);
  auto range = [&](std::uint64_t off, std::uint64_t len, std::size_t field_at, const char* field) {
    if (off > b.size() || len > b.size() - off)
      throw InputError(name, byte_loc(field_at), field,
                       fmt::format("bytes {}..{} lie outside the file ({} bytes): truncated or corrupt", off, off + len,
                                   b.size()));
  };
  if (h.num_frames == 0) throw InputError(name, byte_loc(40), "header num_frames", "no frames");
  if (h.num_tris == 0) throw InputError(name, byte_loc(32), "header num_tris", "no triangles");
  if (h.num_xyz == 0) throw InputError(name, byte_loc(24), "header num_xyz", "no vertices");
  if (std::uint64_t{h.frame_size} < 40 + 4ull * h.num_xyz)
    throw InputError(name, byte_loc(16), "header framesize",
                     fmt::format("{} is too small for {} vertices (needs {})", h.frame_size, h.num_xyz, 40 + 4ull * h.num_xyz));
  range(h.ofs_tris, 12ull * h.num_tris, 52, "triangles (header ofs_tris/num_tris)");
  range(h.ofs_frames, std::uint64_t{h.frame_size} * h.num_frames, 56, "frames (header ofs_frames/num_frames/framesize)");
  for (std::uint32_t t = 0; t < h.num_tris; ++t)
    for (unsigned c = 0; c < 3; ++c) {
      const std::size_t off = h.ofs_tris + 12ull * t + 2 * c;
      const unsigned v = static_cast<unsigned char>(b[off]) | (static_cast<unsigned char>(b[off + 1]) << 8);
      if (v >= h.num_xyz)
        throw InputError(name, byte_loc(off), fmt::format("triangle {} vertex {}", t, c),
                         fmt::format("vertex index {} outside [0, {})", v, h.num_xyz));
    }
  return h;
}

Affine3 to_affine(const aiMatrix4x4& m) {
  Affine3 a = Affine3::Identity();
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 4; ++c) a.matrix()(r, c) = static_cast<double>(m[r][c]);
  return a;
}
Vec3 to_vec(const aiVector3D& v) { return Vec3(v.x, v.y, v.z); }

// Global transform of the root-to-node chain (for the MD2 soup: the root node of an MD2 scene is
// the identity, but we do not rely on it).
void collect_soup(const aiScene& s, const std::string& name, std::vector<Tri>& tris, std::vector<Vec3>& pos) {
  tris.clear();
  pos.clear();
  struct Item {
    const aiNode* n;
    Affine3 g;
  };
  std::vector<Item> stack{{s.mRootNode, to_affine(s.mRootNode->mTransformation)}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    for (unsigned i = 0; i < it.n->mNumMeshes; ++i) {
      const aiMesh* m = s.mMeshes[it.n->mMeshes[i]];
      const auto base = static_cast<std::uint32_t>(pos.size());
      for (unsigned v = 0; v < m->mNumVertices; ++v) pos.push_back(it.g * to_vec(m->mVertices[v]));
      for (unsigned f = 0; f < m->mNumFaces; ++f) {
        const aiFace& face = m->mFaces[f];
        if (face.mNumIndices != 3) continue;
        tris.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
      }
    }
    for (unsigned c = it.n->mNumChildren; c-- > 0;)
      stack.push_back({it.n->mChildren[c], it.g * to_affine(it.n->mChildren[c]->mTransformation)});
  }
  if (tris.empty()) throw InputError(name, "", "", "the imported scene has no triangles");
}

}  // namespace

std::size_t md2_frame_count(const fs::path& path) {
  const std::string b = slurp(path);
  return check_md2(b, path.string()).num_frames;
}

AnimationPtr load_md2(const fs::path& path, const Md2Options& opt) {
  const std::string name = path.string();
  if (!(opt.fps > 0.0) || !std::isfinite(opt.fps)) throw InputError(name, "", "fps", "must be > 0");
  const std::string bytes = slurp(path);
  const Md2Header h = check_md2(bytes, name);
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, kUnusedComponents);
  std::vector<std::vector<Vec3>> frames;
  frames.reserve(h.num_frames);
  std::vector<Tri> tris, tris_k;
  std::vector<Vec3> pos;
  for (std::uint32_t k = 0; k < h.num_frames; ++k) {
    importer.SetPropertyInteger(AI_CONFIG_IMPORT_GLOBAL_KEYFRAME, static_cast<int>(k));
    const aiScene* s = importer.ReadFileFromMemory(
        bytes.data(), bytes.size(), aiProcess_ValidateDataStructure | aiProcess_RemoveComponent, "md2");
    if (!s) throw InputError(name, "", fmt::format("frame {}", k), std::string("assimp: ") + importer.GetErrorString());
    collect_soup(*s, name, k == 0 ? tris : tris_k, pos);
    if (k > 0 && (tris_k != tris || pos.size() != frames.front().size()))
      throw InputError(name, "", fmt::format("frame {}", k), "assimp returned a different topology than for frame 0");
    for (const Vec3& p : pos)
      if (!p.allFinite()) throw InputError(name, "", fmt::format("frame {}", k), "non-finite vertex position");
    frames.push_back(pos);
  }
  std::size_t merged = 0;
  if (opt.weld) {
    const WeldMap w = weld_frames(frames);
    merged = w.merged();
    tris = w.apply(tris);
    for (auto& f : frames) f = w.gather(f);
  }
  const std::size_t nv = frames.front().size(), nt = tris.size();
  return std::make_unique<KeyframeAnimation>(
      std::move(tris), std::move(frames), opt.fps,
      fmt::format("md2 {} ({} frames, {} vertices, {} triangles{})", name, h.num_frames, nv, nt,
                  opt.weld ? fmt::format(", welded {} vertices", merged) : std::string()));
}

// ---------------------------------------------------------------------------------------------
// Skeletal assets

SkinRig skin_rig_from_scene(const aiScene& s, unsigned animation, const std::string& name) {
  if (!s.mRootNode) throw InputError(name, "", "", "the imported scene has no node tree");
  SkinRig rig;
  std::vector<const aiNode*> ai_nodes;
  std::unordered_map<std::string, std::uint32_t> by_name;  // first node of a name (preorder)
  {
    std::vector<std::pair<const aiNode*, std::int32_t>> stack{{s.mRootNode, -1}};
    while (!stack.empty()) {
      const auto [n, parent] = stack.back();
      stack.pop_back();
      const auto idx = static_cast<std::uint32_t>(rig.nodes.size());
      SkeletonNode sn;
      sn.name = n->mName.C_Str();
      sn.parent = parent;
      sn.rest = to_affine(n->mTransformation);
      if (!sn.rest.matrix().allFinite()) throw InputError(name, "", "node '" + sn.name + "'", "non-finite transform");
      rig.nodes.push_back(sn);
      ai_nodes.push_back(n);
      by_name.try_emplace(sn.name, idx);
      for (unsigned c = n->mNumChildren; c-- > 0;) stack.emplace_back(n->mChildren[c], static_cast<std::int32_t>(idx));
    }
  }
  // Animation channels.
  if (s.mNumAnimations > 0) {
    if (animation >= s.mNumAnimations)
      throw InputError(name, "", "animation", fmt::format("animation {} requested, the file has {}", animation, s.mNumAnimations));
    const aiAnimation& a = *s.mAnimations[animation];
    rig.duration_ticks = a.mDuration;
    rig.ticks_per_second = a.mTicksPerSecond > 0.0 ? a.mTicksPerSecond : 25.0;  // assimp's documented default
    for (unsigned c = 0; c < a.mNumChannels; ++c) {
      const aiNodeAnim& ch = *a.mChannels[c];
      const auto it = by_name.find(ch.mNodeName.C_Str());
      if (it == by_name.end()) continue;  // a channel for a node that is not there moves nothing
      SkeletonNode& nd = rig.nodes[it->second];
      if (nd.track >= 0) continue;  // a second channel for one node: the first wins
      NodeTrack tr;
      aiVector3D sc, pos;
      aiQuaternion rot;
      ai_nodes[it->second]->mTransformation.Decompose(sc, rot, pos);
      tr.rest_t = to_vec(pos);
      tr.rest_s = to_vec(sc);
      tr.rest_r = Eigen::Quaterniond(rot.w, rot.x, rot.y, rot.z);
      for (unsigned k = 0; k < ch.mNumPositionKeys; ++k) {
        tr.t_times.push_back(ch.mPositionKeys[k].mTime);
        tr.t_keys.push_back(to_vec(ch.mPositionKeys[k].mValue));
      }
      for (unsigned k = 0; k < ch.mNumRotationKeys; ++k) {
        const aiQuaternion& q = ch.mRotationKeys[k].mValue;
        tr.r_times.push_back(ch.mRotationKeys[k].mTime);
        tr.r_keys.emplace_back(q.w, q.x, q.y, q.z);
      }
      for (unsigned k = 0; k < ch.mNumScalingKeys; ++k) {
        tr.s_times.push_back(ch.mScalingKeys[k].mTime);
        tr.s_keys.push_back(to_vec(ch.mScalingKeys[k].mValue));
      }
      for (const auto& q : tr.r_keys)
        if (!q.coeffs().allFinite() || q.norm() == 0.0)
          throw InputError(name, "", fmt::format("channel '{}'", ch.mNodeName.C_Str()), "bad rotation key");
      nd.track = static_cast<std::int32_t>(rig.tracks.size());
      rig.tracks.push_back(std::move(tr));
    }
  }
  // Meshes of every node instance, in node order.
  rig.influence_begin.push_back(0);
  for (std::uint32_t n = 0; n < ai_nodes.size(); ++n) {
    const aiNode* node = ai_nodes[n];
    for (unsigned mi = 0; mi < node->mNumMeshes; ++mi) {
      const aiMesh& m = *s.mMeshes[node->mMeshes[mi]];
      const std::string mesh_el = fmt::format("mesh {} ('{}')", node->mMeshes[mi], m.mName.C_Str());
      bool has_tri = false;
      for (unsigned f = 0; f < m.mNumFaces && !has_tri; ++f) has_tri = m.mFaces[f].mNumIndices == 3;
      if (!has_tri) continue;  // points and lines only
      const auto base = static_cast<std::uint32_t>(rig.bind_positions.size());
      // Per vertex influences of this mesh.
      std::vector<std::vector<SkinInfluence>> inf(m.mNumVertices);
      for (unsigned b = 0; b < m.mNumBones; ++b) {
        const aiBone& bone = *m.mBones[b];
        const auto it = by_name.find(bone.mName.C_Str());
        if (it == by_name.end())
          throw InputError(name, "", fmt::format("{} bone '{}'", mesh_el, bone.mName.C_Str()), "no node of that name");
        const Affine3 off = to_affine(bone.mOffsetMatrix);
        if (!off.matrix().allFinite())
          throw InputError(name, "", fmt::format("{} bone '{}'", mesh_el, bone.mName.C_Str()), "non-finite offset matrix");
        const auto pal = static_cast<std::uint32_t>(rig.palette_node.size());
        rig.palette_node.push_back(it->second);
        rig.palette_offset.push_back(off);
        for (unsigned w = 0; w < bone.mNumWeights; ++w) {
          const aiVertexWeight& vw = bone.mWeights[w];
          if (vw.mVertexId >= m.mNumVertices)
            throw InputError(name, "", fmt::format("{} bone '{}' weight {}", mesh_el, bone.mName.C_Str(), w),
                             fmt::format("vertex {} outside [0, {})", vw.mVertexId, m.mNumVertices));
          if (!std::isfinite(vw.mWeight) || vw.mWeight < 0.0f)
            throw InputError(name, "", fmt::format("{} bone '{}' weight {}", mesh_el, bone.mName.C_Str(), w),
                             fmt::format("bad weight {}", vw.mWeight));
          if (vw.mWeight > 0.0f) inf[vw.mVertexId].push_back({pal, static_cast<double>(vw.mWeight)});
        }
      }
      // The mesh node itself, for meshes without bones and vertices no bone moves.
      std::uint32_t own = std::numeric_limits<std::uint32_t>::max();
      for (unsigned v = 0; v < m.mNumVertices; ++v) {
        const Vec3 p = to_vec(m.mVertices[v]);
        if (!p.allFinite()) throw InputError(name, "", fmt::format("{} vertex {}", mesh_el, v), "non-finite position");
        rig.bind_positions.push_back(p);
        if (inf[v].empty()) {
          if (own == std::numeric_limits<std::uint32_t>::max()) {
            own = static_cast<std::uint32_t>(rig.palette_node.size());
            rig.palette_node.push_back(n);
            rig.palette_offset.push_back(Affine3::Identity());
          }
          inf[v].push_back({own, 1.0});
        }
        rig.influences.insert(rig.influences.end(), inf[v].begin(), inf[v].end());
        rig.influence_begin.push_back(static_cast<std::uint32_t>(rig.influences.size()));
      }
      for (unsigned f = 0; f < m.mNumFaces; ++f) {
        const aiFace& face = m.mFaces[f];
        if (face.mNumIndices != 3) continue;
        Tri t;
        for (unsigned c = 0; c < 3; ++c) {
          if (face.mIndices[c] >= m.mNumVertices)
            throw InputError(name, "", fmt::format("{} face {}", mesh_el, f), "vertex index out of range");
          t[c] = base + face.mIndices[c];
        }
        rig.triangles.push_back(t);
      }
    }
  }
  if (rig.triangles.empty()) throw InputError(name, "", "", "the scene has no triangle mesh");
  return rig;
}

namespace {
/// Whether every mesh of the scene is assimp's SkeletonMeshBuilder's stand-in for a file without
/// meshes (BVH motion capture and the like): the builder names its one material "SkeletonMaterial".
bool skeleton_stand_in(const aiScene& s) {
  if (s.mNumMeshes == 0) return false;
  for (unsigned k = 0; k < s.mNumMeshes; ++k) {
    const aiMesh* m = s.mMeshes[k];
    if (m->mMaterialIndex >= s.mNumMaterials) return false;
    aiString mat;
    if (s.mMaterials[m->mMaterialIndex]->Get(AI_MATKEY_NAME, mat) != AI_SUCCESS) return false;
    if (std::string_view(mat.C_Str()) != "SkeletonMaterial") return false;
  }
  return true;
}
}  // namespace

AnimationPtr load_assimp_animation(const fs::path& path, const AssimpSkinOptions& opt) {
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(name, "", "", "no such file");
  if (fs::is_directory(path, ec)) throw InputError(name, "", "", "is a directory, not a file");
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, kUnusedComponents);
  note_input_file(path);
  // Read, look at the materials (before RemoveComponent drops them), then post-process.
  const aiScene* s = importer.ReadFile(path.string(), aiProcess_ValidateDataStructure);
  if (!s) throw InputError(name, "", "", std::string("assimp: ") + importer.GetErrorString());
  if (s->mFlags & AI_SCENE_FLAGS_INCOMPLETE) throw InputError(name, "", "", "assimp: incomplete scene (no meshes)");
  if (skeleton_stand_in(*s))
    throw InputError(name, "", "",
                     "has motion data only, no mesh (assimp draws the skeleton's bones as a stand-in mesh, which ptc does "
                     "not trace): use a file with the mesh and its animation together (FBX, COLLADA, glTF, MD5 mesh)");
  s = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_RemoveComponent);  // (validated on reading)
  if (!s) throw InputError(name, "", "", std::string("assimp: ") + importer.GetErrorString());
  SkinRig rig = skin_rig_from_scene(*s, opt.animation, name);
  const std::string label = fmt::format("{} ({} meshes, animation {} of {})", name, s->mNumMeshes,
                                        s->mNumAnimations ? opt.animation : 0, s->mNumAnimations);
  try {
    auto anim = std::make_unique<SkinnedAnimation>(std::move(rig), opt.skin, label);
    if (anim->is_static())
      return std::make_unique<StaticSource>(anim->rest(), fmt::format("{} (no animation)", name));
    return anim;
  } catch (const std::invalid_argument& e) {
    throw InputError(name, "", "", e.what());
  }
}

}  // namespace ptc

// Skeletal animation (toolkit/anim/skinning.h, assimp_source.h): a two-bone rig built as an
// aiScene in memory against hand-derived positions; BCN_Epileptic.X against an independent
// evaluation written with assimp's own float math (aiMatrix4x4, aiQuaternion::Interpolate);
// welding against the unwelded rig; allocation-free positions() for every in-memory source.
#include <gtest/gtest.h>
#include <unistd.h>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <sstream>

#include "toolkit/anim/assimp_source.h"
#include "toolkit/anim/frame_sequence.h"
#include "toolkit/anim/md3.h"
#include "toolkit/anim/skinning.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

// Counting allocator for the allocation-free checks: counts only while g_count is set. It
// replaces the global operator new of this test program (malloc-backed, as the default one);
// GCC's mismatched-new-delete check cannot see that new and delete here pair up.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
namespace {
std::atomic<bool> g_count{false};
std::atomic<long> g_allocs{0};
}  // namespace
void* operator new(std::size_t n) {
  if (g_count.load(std::memory_order_relaxed)) g_allocs.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

// LeakSanitizer (PTC_SANITIZE=1 builds): assimp 5.2.5 (Debian 12) leaks the partly built scene
// when its X parser meets a truncated file - reproduced with a bare Assimp::Importer::ReadFile on
// a cut BCN_Epileptic.X, no ptc code involved - and a test below feeds it such a file on purpose.
// Only leaks allocated from inside libassimp are suppressed.
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

namespace ptc {
namespace {

namespace fs = std::filesystem;
const fs::path kBcn = "/usr/share/assimp/models/X/BCN_Epileptic.X";

std::vector<Vec3> positions_at(Animation& a, double t) {
  std::vector<Vec3> p(a.rest().vertex_count());
  a.positions(t, p);
  return p;
}

// ---------------------------------------------------------------------------------------------
// Two bones, built in memory.
//
//   root
//   |- mesh_node   (translation (0, 0, 5); holds the mesh)
//   '- bone1       (rest identity)
//      '- bone2    (rest translation (1, 0, 0))
// Bind pose = rest pose, so offset1 = I, offset2 = T(-1, 0, 0).
// Animation: 10 ticks at 10 ticks/s; bone1 and bone2 rotate from identity to 90 degrees about z.
// Vertices:  0 (0.5, 0, 0)  bone1 only
//            1 (1.5, 0, 0)  bone1 0.25, bone2 0.75
//            2 (2, 0, 0)    bone2 only
//            3 (1, 0, 0)    bone1 2, bone2 2 (unnormalised -> halves)
//            4 (0, 1, 0)    no weights -> mesh_node's transform
//            5 = copy of 0 (same weights: welds with 0), 6 = copy of 0 weighted to bone2 (must not)
aiScene* two_bone_scene() {
  auto* s = new aiScene();
  s->mRootNode = new aiNode("root");
  auto* mesh_node = new aiNode("mesh_node");
  auto* b1 = new aiNode("bone1");
  auto* b2 = new aiNode("bone2");
  mesh_node->mTransformation = aiMatrix4x4::Translation(aiVector3D(0, 0, 5), mesh_node->mTransformation);
  b2->mTransformation = aiMatrix4x4::Translation(aiVector3D(1, 0, 0), b2->mTransformation);
  s->mRootNode->addChildren(2, std::array<aiNode*, 2>{mesh_node, b1}.data());
  b1->addChildren(1, &b2);
  mesh_node->mNumMeshes = 1;
  mesh_node->mMeshes = new unsigned[1]{0};

  auto* m = new aiMesh();
  m->mName = "strip";
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  const aiVector3D v[] = {{0.5f, 0, 0}, {1.5f, 0, 0}, {2, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5f, 0, 0}, {0.5f, 0, 0}};
  m->mNumVertices = 7;
  m->mVertices = new aiVector3D[7];
  std::copy(std::begin(v), std::end(v), m->mVertices);
  const unsigned f[][3] = {{0, 1, 4}, {1, 2, 4}, {1, 3, 2}, {5, 6, 3}};
  m->mNumFaces = 4;
  m->mFaces = new aiFace[4];
  for (int i = 0; i < 4; ++i) {
    m->mFaces[i].mNumIndices = 3;
    m->mFaces[i].mIndices = new unsigned[3]{f[i][0], f[i][1], f[i][2]};
  }
  auto* bone1 = new aiBone();
  bone1->mName = "bone1";
  bone1->mNumWeights = 4;
  bone1->mWeights = new aiVertexWeight[4]{{0, 1.0f}, {1, 0.25f}, {3, 2.0f}, {5, 1.0f}};
  auto* bone2 = new aiBone();
  bone2->mName = "bone2";
  bone2->mOffsetMatrix = aiMatrix4x4::Translation(aiVector3D(-1, 0, 0), bone2->mOffsetMatrix);
  bone2->mNumWeights = 4;
  bone2->mWeights = new aiVertexWeight[4]{{1, 0.75f}, {2, 1.0f}, {3, 2.0f}, {6, 1.0f}};
  m->mNumBones = 2;
  m->mBones = new aiBone*[2]{bone1, bone2};
  s->mNumMeshes = 1;
  s->mMeshes = new aiMesh*[1]{m};

  auto* anim = new aiAnimation();
  anim->mDuration = 10.0;
  anim->mTicksPerSecond = 10.0;
  anim->mNumChannels = 2;
  anim->mChannels = new aiNodeAnim*[2];
  const aiQuaternion q0(1, 0, 0, 0), q90(aiVector3D(0, 0, 1), static_cast<float>(M_PI / 2));
  for (int c = 0; c < 2; ++c) {
    auto* ch = new aiNodeAnim();
    ch->mNodeName = c == 0 ? "bone1" : "bone2";
    ch->mNumRotationKeys = 2;
    ch->mRotationKeys = new aiQuatKey[2]{aiQuatKey(0.0, q0), aiQuatKey(10.0, q90)};
    ch->mNumPositionKeys = 1;
    ch->mPositionKeys = new aiVectorKey[1]{aiVectorKey(0.0, aiVector3D(c == 0 ? 0.0f : 1.0f, 0, 0))};
    ch->mNumScalingKeys = 1;
    ch->mScalingKeys = new aiVectorKey[1]{aiVectorKey(0.0, aiVector3D(1, 1, 1))};
    anim->mChannels[c] = ch;
  }
  s->mNumAnimations = 1;
  s->mAnimations = new aiAnimation*[1]{anim};
  return s;
}

void expect_near(const Vec3& got, const Vec3& want, const char* what) {
  EXPECT_LE((got - want).norm(), 1e-6) << what << ": got (" << got.transpose() << ") want (" << want.transpose() << ")";
}

TEST(AnimSkinning, TwoBonesMatchHandDerivedPositions) {
  std::unique_ptr<aiScene> scene(two_bone_scene());
  for (bool weld : {false, true}) {
    SkinOptions o;
    o.weld = weld;
    SkinnedAnimation a(skin_rig_from_scene(*scene, 0, "two_bone"), o, "two_bone");
    EXPECT_EQ(a.frame_count(), 31u);  // 1 s at 30 fps: frames 0..30
    EXPECT_FALSE(a.is_static());
    EXPECT_EQ(a.merged_vertices(), weld ? 1u : 0u);  // only vertex 5 (twin of 0, same weights)
    const std::size_t nv = weld ? 6 : 7;
    ASSERT_EQ(a.rest().vertex_count(), nv);
    // Welded ids: 0 1 2 3 4 (5 -> 0) 6 -> 5.
    auto id = [&](std::size_t v) { return weld ? (v == 5 ? 0 : v == 6 ? 5 : v) : v; };
    const double c = std::sqrt(0.5);
    // Rest (= bind) pose: vertices where they are; the unweighted one moved by mesh_node.
    const auto r = a.rest().positions();
    expect_near(r[id(0)], Vec3(0.5, 0, 0), "rest 0");
    expect_near(r[id(2)], Vec3(2, 0, 0), "rest 2");
    expect_near(r[id(4)], Vec3(0, 1, 5), "rest 4");
    // t = 0: identity rotations.
    auto p = positions_at(a, 0);
    expect_near(p[id(1)], Vec3(1.5, 0, 0), "t0 v1");
    // t = 1 s (frame 30): bone1 = Rz90, bone2 global = Rz90 T(1,0,0) Rz90.
    p = positions_at(a, 30);
    expect_near(p[id(0)], Vec3(0, 0.5, 0), "t30 v0");
    expect_near(p[id(1)], Vec3(-0.375, 1.125, 0), "t30 v1");  // 0.25 (0, 1.5) + 0.75 (-0.5, 1)
    expect_near(p[id(2)], Vec3(-1, 1, 0), "t30 v2");
    expect_near(p[id(3)], Vec3(0, 1, 0), "t30 v3");  // both bones map (1,0,0) to (0,1,0)
    expect_near(p[id(4)], Vec3(0, 1, 5), "t30 v4");
    expect_near(p[id(6)], Vec3(0.5, 1, 0), "t30 v6");  // bone2: (-0.5,0) -> (0,-0.5) -> (1,-0.5) -> (0.5,1)
    // t = 0.5 s (frame 15): slerp gives Rz45 for both bones.
    p = positions_at(a, 15);
    expect_near(p[id(0)], Vec3(0.5 * c, 0.5 * c, 0), "t15 v0");
    expect_near(p[id(2)], Vec3(c, 1 + c, 0), "t15 v2");
    // Fractional frame 7.5 = 0.25 s = Rz22.5.
    p = positions_at(a, 7.5);
    const double a22 = M_PI / 8;
    expect_near(p[id(0)], Vec3(0.5 * std::cos(a22), 0.5 * std::sin(a22), 0), "t7.5 v0");
    // After the last key the last pose holds (positions_at_ticks has no range check).
    std::vector<Vec3> q(nv);
    a.positions_at_ticks(25.0, q);
    expect_near(q[id(2)], Vec3(-1, 1, 0), "after last key");
    a.positions_at_ticks(-3.0, q);
    expect_near(q[id(2)], Vec3(2, 0, 0), "before first key");
    EXPECT_THROW(a.positions(30.5, q), std::out_of_range);
    EXPECT_THROW(a.positions(-1, q), std::out_of_range);
  }
}

TEST(AnimSkinning, BadRigsAreRejected) {
  std::unique_ptr<aiScene> scene(two_bone_scene());
  scene->mMeshes[0]->mBones[1]->mName = "no_such_bone";
  try {
    (void)skin_rig_from_scene(*scene, 0, "rig.dae");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rig.dae"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("bone 'no_such_bone'"), std::string::npos) << e.what();
  }
  scene.reset(two_bone_scene());
  scene->mMeshes[0]->mBones[0]->mWeights[0].mVertexId = 99;
  EXPECT_THROW((void)skin_rig_from_scene(*scene, 0, "rig.dae"), InputError);
  scene.reset(two_bone_scene());
  scene->mMeshes[0]->mBones[0]->mWeights[0].mWeight = std::nanf("");
  EXPECT_THROW((void)skin_rig_from_scene(*scene, 0, "rig.dae"), InputError);
  scene.reset(two_bone_scene());
  EXPECT_THROW((void)skin_rig_from_scene(*scene, 3, "rig.dae"), InputError);  // no animation 3
  // Keys out of order are a validate() error.
  SkinRig rig = skin_rig_from_scene(*scene, 0, "rig.dae");
  rig.tracks[0].r_times = {10.0, 0.0};
  EXPECT_THROW(SkinnedAnimation(rig, {}, "x"), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// BCN_Epileptic.X against an independent evaluation in assimp's float math.

aiMatrix4x4 eval_node(const aiNode* n, const aiAnimation& a, double ticks) {
  aiMatrix4x4 local = n->mTransformation;
  for (unsigned c = 0; c < a.mNumChannels; ++c) {
    const aiNodeAnim* ch = a.mChannels[c];
    if (ch->mNodeName != n->mName) continue;
    auto vec = [&](const aiVectorKey* k, unsigned nk) {
      if (ticks <= k[0].mTime) return k[0].mValue;
      for (unsigned i = 0; i + 1 < nk; ++i)
        if (ticks < k[i + 1].mTime) {
          const auto f = static_cast<float>((ticks - k[i].mTime) / (k[i + 1].mTime - k[i].mTime));
          return k[i].mValue + (k[i + 1].mValue - k[i].mValue) * f;
        }
      return k[nk - 1].mValue;
    };
    aiQuaternion r = ch->mRotationKeys[0].mValue;
    for (unsigned i = 0; i + 1 < ch->mNumRotationKeys; ++i)
      if (ticks >= ch->mRotationKeys[i].mTime && ticks < ch->mRotationKeys[i + 1].mTime) {
        const auto f = static_cast<float>((ticks - ch->mRotationKeys[i].mTime) /
                                          (ch->mRotationKeys[i + 1].mTime - ch->mRotationKeys[i].mTime));
        aiQuaternion::Interpolate(r, ch->mRotationKeys[i].mValue, ch->mRotationKeys[i + 1].mValue, f);
      }
    if (ch->mNumRotationKeys > 1 && ticks >= ch->mRotationKeys[ch->mNumRotationKeys - 1].mTime)
      r = ch->mRotationKeys[ch->mNumRotationKeys - 1].mValue;
    r.Normalize();
    const aiVector3D t = vec(ch->mPositionKeys, ch->mNumPositionKeys), s = vec(ch->mScalingKeys, ch->mNumScalingKeys);
    aiMatrix4x4 S, T;
    aiMatrix4x4::Scaling(s, S);
    aiMatrix4x4::Translation(t, T);
    local = T * aiMatrix4x4(r.GetMatrix()) * S;
    break;
  }
  return n->mParent ? eval_node(n->mParent, a, ticks) * local : local;
}

TEST(AnimSkinning, EpilepticMatchesAnIndependentEvaluation) {
  Assimp::Importer imp;
  const aiScene* s = imp.ReadFile(kBcn.string(), aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  ASSERT_NE(s, nullptr) << imp.GetErrorString();
  ASSERT_EQ(s->mNumAnimations, 1u);
  const aiAnimation& an = *s->mAnimations[0];
  AssimpSkinOptions o;
  o.skin.weld = false;
  auto a = load_assimp_animation(kBcn, o);
  auto w = load_assimp_animation(kBcn);  // welded
  const double tps = an.mTicksPerSecond;
  EXPECT_EQ(a->frame_count(), static_cast<std::size_t>(std::floor(an.mDuration / tps * 30.0 + 1e-9)) + 1);
  std::size_t faces = 0, verts = 0;
  for (unsigned m = 0; m < s->mNumMeshes; ++m) faces += s->mMeshes[m]->mNumFaces, verts += s->mMeshes[m]->mNumVertices;
  ASSERT_EQ(a->rest().triangle_count(), faces);
  ASSERT_EQ(a->rest().vertex_count(), verts);
  ASSERT_EQ(w->rest().triangle_count(), faces);
  EXPECT_LT(w->rest().vertex_count(), verts / 2);  // the .X meshes are nearly soups
  const Box3 rest_box = a->rest().bounds();
  const double diag = rest_box.extent().norm();
  double max_move = 0.0;
  for (double frame : {0.0, 17.5, 49.0, 80.25}) {
    const double ticks = frame / 30.0 * tps;
    const auto p = positions_at(*a, frame);
    const auto pw = positions_at(*w, frame);
    // Independent LBS per mesh (meshes are attached to root children, in node order).
    std::size_t base = 0;
    std::vector<const aiMesh*> order;
    std::vector<const aiNode*> stack{s->mRootNode};
    while (!stack.empty()) {
      const aiNode* n = stack.back();
      stack.pop_back();
      for (unsigned i = 0; i < n->mNumMeshes; ++i) order.push_back(s->mMeshes[n->mMeshes[i]]);
      for (unsigned c = n->mNumChildren; c-- > 0;) stack.push_back(n->mChildren[c]);
    }
    for (const aiMesh* m : order) {
      std::vector<aiVector3D> acc(m->mNumVertices, aiVector3D(0, 0, 0));
      std::vector<float> wsum(m->mNumVertices, 0.0f);
      for (unsigned b = 0; b < m->mNumBones; ++b) {
        const aiBone* bone = m->mBones[b];
        const aiMatrix4x4 M = eval_node(s->mRootNode->FindNode(bone->mName), an, ticks) * bone->mOffsetMatrix;
        for (unsigned k = 0; k < bone->mNumWeights; ++k) {
          const auto& vw = bone->mWeights[k];
          acc[vw.mVertexId] += (M * m->mVertices[vw.mVertexId]) * vw.mWeight;
          wsum[vw.mVertexId] += vw.mWeight;
        }
      }
      for (unsigned v = 0; v < m->mNumVertices; ++v) {
        ASSERT_GT(wsum[v], 0.0f);
        const aiVector3D q = acc[v] / wsum[v];
        const Vec3& got = p[base + v];
        ASSERT_TRUE(got.allFinite());
        ASSERT_LE((got - Vec3(q.x, q.y, q.z)).norm(), 1e-5 * diag) << "frame " << frame << " vertex " << base + v;
        max_move = std::max(max_move, (got - a->rest().position(base + v)).norm());
      }
      base += m->mNumVertices;
    }
    // Welded = unwelded, corner by corner, bit for bit.
    for (std::size_t t = 0; t < faces; ++t)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(pw[w->rest().triangle(t)[c]], p[a->rest().triangle(t)[c]]);
    // Bounded: nothing leaves a box ten times the rest size.
    for (const Vec3& q : p) ASSERT_LE((q - rest_box.center()).norm(), 10.0 * diag);
  }
  EXPECT_GT(max_move, 0.05 * diag);  // it really moves
}

TEST(AnimSkinning, OtherFormatsWithBonesAnimate) {
  // FBX (Blender armature) and glTF 2 (simple_skin): they load, move, and stay finite and bounded.
  for (const char* f : {"FBX/animation_with_skeleton.fbx", "glTF2/simple_skin/simple_skin.gltf"}) {
    auto a = load_assimp_animation(std::string("/usr/share/assimp/models/") + f);
    ASSERT_FALSE(a->is_static()) << f;
    ASSERT_GT(a->frame_count(), 2u) << f;
    const Box3 box = a->rest().bounds();
    const double diag = box.extent().norm();
    double moved = 0.0;
    for (std::size_t k = 0; k < a->frame_count(); k += 3) {
      const auto p = positions_at(*a, static_cast<double>(k));
      for (std::size_t v = 0; v < p.size(); ++v) {
        ASSERT_TRUE(p[v].allFinite()) << f;
        ASSERT_LE((p[v] - box.center()).norm(), 10.0 * diag) << f;
        moved = std::max(moved, (p[v] - a->rest().position(v)).norm());
      }
    }
    EXPECT_GT(moved, 1e-3 * diag) << f;
  }
}

TEST(AnimSkinning, FilesWithoutAnimationAreStaticAndBadFilesAreInputErrors) {
  auto st = load_assimp_animation("/usr/share/assimp/models/FBX/spider.fbx");
  EXPECT_TRUE(st->is_static());
  EXPECT_GT(st->rest().triangle_count(), 0u);
  const fs::path dir = fs::temp_directory_path() / ("ptc_anim_skin_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ifstream in(kBcn, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string b = ss.str();
  {
    std::ofstream out(dir / "cut.x", std::ios::binary);
    out << b.substr(0, b.size() / 3);
  }
  try {
    (void)load_assimp_animation(dir / "cut.x");
    ADD_FAILURE() << "truncated .x accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.x"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)load_assimp_animation(dir / "missing.x"), InputError);
  fs::remove_all(dir);
  // Motion capture without a mesh (BVH): assimp's skeleton stand-in is refused, naming the file
  // and the reason; a file whose mesh has bones of its own still loads (above).
  for (const char* f : {"BVH/01_01.bvh", "BVH/Boxing_Toes.bvh"}) {
    const std::string file = std::string("/usr/share/assimp/models/") + f;
    try {
      (void)load_assimp_animation(file);
      ADD_FAILURE() << f << ": the skeleton stand-in was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("motion data only"), std::string::npos) << e.what();
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Allocation-free per frame (after one warm-up call).

long allocations_during(Animation& a, std::initializer_list<double> times) {
  std::vector<Vec3> out(a.rest().vertex_count());
  a.positions(*times.begin(), out);  // warm-up
  g_allocs = 0;
  g_count = true;
  for (double t : times) a.positions(t, out);
  g_count = false;
  return g_allocs.load();
}

TEST(AnimSkinning, PositionsDoNotAllocate) {
  auto skinned = load_assimp_animation(kBcn);
  EXPECT_EQ(allocations_during(*skinned, {0.0, 10.5, 42.0, 99.0}), 0);
  AssimpSkinOptions raw;
  raw.skin.weld = false;  // 15k vertices: the parallel path
  auto skinned_raw = load_assimp_animation(kBcn, raw);
  EXPECT_EQ(allocations_during(*skinned_raw, {0.0, 10.5, 42.0}), 0);
  auto md2 = load_md2("/usr/share/assimp/models/MD2/faerie.md2");
  EXPECT_EQ(allocations_during(*md2, {0.0, 10.5, 197.0}), 0);
  // The counter is live: a lazy frame sequence reads (allocates) when a new frame is needed.
  const fs::path dir = fs::temp_directory_path() / ("ptc_anim_alloc_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const Mesh m({{0, 1, 2}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
  write_mesh(dir / "f0.obj", m);
  write_mesh(dir / "f1.obj", m.with_positions({Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0, 1, 1)}));
  FrameSequence lazy(dir.string());
  EXPECT_GT(allocations_during(lazy, {0.0, 1.0}), 0);
  FrameSequenceOptions eager;
  eager.loading = FrameLoading::Eager;
  FrameSequence pre(dir.string(), eager);
  EXPECT_EQ(allocations_during(pre, {0.0, 0.5, 1.0}), 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ptc

// `ptc experiment accuracy`: speed against error of every approximation the toolkit makes, one
// row per choice and frame (accuracy.csv, schema ptc-accuracy/1; docs/experiments.md):
//
//   sphere/M            bounding sphere M alone on the clusters of the method's clustering
//                       (contraction with Acc, or --clusters DIR) at the frame, against the exact minimal sphere (CGAL, exact arithmetic):
//                       ns per sphere, relative radius error mean and max;
//   sphere_in_loop/M    contraction with Acc made with M inside the objective, against the same
//                       made with the CGAL working path (always re-clustered, also with
//                       --clusters): clustering time, the clusters' mean Acc (evaluated with CGAL),
//                       the cluster BVH's SAH cost and primary trace time at the frame;
//   builder/T           the exact sweep SAH builder against the binned one (T = triangles or
//                       clusters; plain builds): the SAH build's time (the `build` stage alone),
//                       SAH cost and primary trace time at the frame;
//   groups/two_level    the two-level cluster BVH build against the plain one: update + build
//                       time, SAH cost and primary trace time (both built at the frame's pose,
//                       where fixed group trees, bvh::GroupTrees::Refit, are the rebuilt ones);
//   hits/C              closest hits of configuration C (ours_triangles, ours_clusters,
//                       embree_low, embree_medium; float, in the trace frame) against a double
//                       brute force over every triangle on a seeded sample of the primary rays:
//                       mismatches (hit/miss, another triangle beyond the tie rule), ties, and
//                       the relative t error where both hit the same triangle; time_ms = the
//                       configuration's trace of all primary rays, reference_time_ms = the brute
//                       force over the sample, speedup = per-ray time of the reference / of C.
#pragma once

#include <string>
#include <vector>

#include "analysis/experiments/experiments.h"

namespace ptc {

/// The accuracy items (choices), in order.
[[nodiscard]] std::vector<std::string> accuracy_items(bool given);

struct AccuracyRun {
  std::vector<FileRows> files;  ///< accuracy.csv
  std::size_t rays = 0;
};
/// Runs the items `done` (indices into `items`) over setup.frames. Its own loop over the frames,
/// not the study loop: every item builds its structures from scratch at the frame's positions
/// (two builders, two group sizes, a sphere method), nothing is updated from frame to frame.
[[nodiscard]] AccuracyRun run_accuracy(Scene& scene, const ExperimentParams& p, const study::StudySetup& setup,
                                       const std::vector<std::string>& items, const std::vector<std::size_t>& done);

/// The printed table of accuracy.csv.
[[nodiscard]] std::string accuracy_text(const CsvText& accuracy);

}  // namespace ptc

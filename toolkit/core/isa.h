// Run-time dispatch of the clustering's hot functions by instruction set.
#pragma once

/// PTC_ISA_CLONES before a function definition compiles it twice, for x86-64-v3 (AVX2, BMI1/2,
/// LZCNT, MOVBE: CPUs since about 2013-2015) and for the baseline x86-64 every Debian amd64 machine
/// has; the dynamic loader picks one when the program starts (GCC's target_clones, an ifunc).
/// The results are the same bits either way: the project compiles in ISO C++ mode, where GCC
/// contracts no a * b + c into a fused multiply-add (-ffp-contract=off, also set explicitly on
/// the toolkit), and Eigen chooses its vector code by the translation unit's macros (__AVX__),
/// which a function's target does not change, so only the encoding and the scalar instructions
/// differ. Measured on the growth at 13.3M triangles: docs/scale.md, "Open (issue 15)".
/// Clang builds (the fuzzing build) and other architectures get the one baseline version, as does
/// a build with -DPTC_NO_ISA_CLONES.
/// Exceptions: GCC 12 compiles a call to such a function as one that cannot throw. A caller
/// that only tail-calls it is fine; a caller with cleanups or a throw of its own gets no
/// call-site entry for that call, and an exception from the clone then terminates the program
/// (found when grow_clusters got a check of its own: Regions.StopsOnRequest... aborted). Put
/// checks that throw inside the cloned function.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(PTC_NO_ISA_CLONES)
#define PTC_HAS_ISA_CLONES 1
#define PTC_ISA_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define PTC_HAS_ISA_CLONES 0
#define PTC_ISA_CLONES
#endif

namespace ptc {

/// The instruction set whose clones the loader picked for this process: "x86-64-v3" or "x86-64"
/// (the baseline; also every build without the clones). Recorded in every manifest
/// (`machine.clustering_isa`), since the clustering's times depend on it.
[[nodiscard]] const char* clustering_isa();

}  // namespace ptc

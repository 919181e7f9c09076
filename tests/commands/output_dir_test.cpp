// Output directories written whole or not at all, and the inputs recorded in manifests.
#include <gtest/gtest.h>
#include <unistd.h>

#include <charconv>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "toolkit/core/error.h"
#include "common/temp_dir.h"

namespace ptc {
namespace {
namespace fs = std::filesystem;

using test::slurp;

TEST(OutputDir, CommitReplacesAndFailureKeepsTheOld) {
  const fs::path base = fs::temp_directory_path() / ("ptc_outdir_" + std::to_string(::getpid()));
  fs::remove_all(base);
  const fs::path target = base / "nested" / "run";
  {
    OutputDir d(target);
    d.write("a.csv", "first\n");
    EXPECT_FALSE(fs::exists(target));  // nothing visible before commit
    d.commit();
  }
  EXPECT_EQ(slurp(target / "a.csv"), "first\n");
  {
    OutputDir d(target);
    d.write("a.csv", "second\n");
    // destroyed without commit: a failed run
  }
  EXPECT_EQ(slurp(target / "a.csv"), "first\n");
  {
    OutputDir d(target);
    d.write("b.csv", "third\n");
    d.commit();
  }
  EXPECT_FALSE(fs::exists(target / "a.csv"));  // the whole directory was replaced
  EXPECT_EQ(slurp(target / "b.csv"), "third\n");
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(base / "nested")) ++entries;
  EXPECT_EQ(entries, 1u);  // no temporaries left behind
  // A file where the directory should go is a clear error.
  std::ofstream(base / "file") << "x";
  EXPECT_THROW(OutputDir(base / "file"), InputError);
  fs::remove_all(base);
}

TEST(OutputDir, NeverReplacesADirectoryItDidNotWrite) {
  const fs::path base = fs::temp_directory_path() / ("ptc_outdir2_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base / "precious");
  std::ofstream(base / "precious" / "thesis.txt") << "years of work";
  try {
    OutputDir d(base / "precious");
    FAIL() << "a foreign directory was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("precious"), std::string::npos) << e.what();
  }
  EXPECT_EQ(slurp(base / "precious" / "thesis.txt"), "years of work");
  // An empty directory is fine, and so is a trailing separator.
  fs::create_directories(base / "empty");
  {
    OutputDir d(base / "empty/");
    d.write("x.csv", "1\n");
    d.commit();
    EXPECT_EQ(d.target(), base / "empty");
  }
  EXPECT_EQ(slurp(base / "empty" / "x.csv"), "1\n");
  EXPECT_TRUE(fs::exists(base / "empty" / OutputDir::kMarker));
  // ... and the marked directory can be replaced by the next run.
  {
    OutputDir d(base / "empty");
    d.write("y.csv", "2\n");
    d.commit();
  }
  EXPECT_FALSE(fs::exists(base / "empty" / "x.csv"));
  EXPECT_THROW(OutputDir(base / ".."), InputError);
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(base)) ++entries;
  EXPECT_EQ(entries, 2u);  // precious and empty, no temporaries
  fs::remove_all(base);
}

TEST(Manifest, HashIsFnv1aAndRecordsEverything) {
  const fs::path p = fs::temp_directory_path() / ("ptc_hash_" + std::to_string(::getpid()));
  std::ofstream(p, std::ios::binary) << "a";
  // FNV-1a 64 of "a" (published test vector).
  EXPECT_EQ(file_fnv1a64(p), "af63dc4c8601ec8c");
  std::ofstream(p, std::ios::binary | std::ios::trunc) << "";
  EXPECT_EQ(file_fnv1a64(p), "cbf29ce484222325");
  EXPECT_THROW((void)file_fnv1a64(p.string() + ".missing"), InputError);
  RunManifest m("test", {"ptc", "test"});
  record_input(m, p);
  m.set_parameter("k", 3);
  m.add_timing_ms("stage", 1.5);
  const auto j = m.to_json();
  EXPECT_EQ(j["parameters"]["k"], 3);
  EXPECT_EQ(j["timings_ms"]["stage"], 1.5);
  EXPECT_EQ(j["inputs"][0]["bytes"], 0);
  EXPECT_EQ(j["build"]["git_commit"].get<std::string>().size() >= 7 || j["build"]["git_commit"] == "unknown", true);
  fs::remove(p);
}

// A rerun into a ptc output directory keeps what the user added there (and says so), drops
// ptc's own stale files, and keeps a user's file whose name the new run writes as NAME.kept.
TEST(OutputDir, RerunKeepsFilesTheUserAdded) {
  const fs::path base = fs::temp_directory_path() / ("ptc_keep_" + std::to_string(::getpid()));
  fs::remove_all(base);
  const fs::path target = base / "out";
  {
    OutputDir d(target);
    d.write("a.csv", "first a");
    d.write("stale.csv", "only in the first run");
    d.commit();
    EXPECT_TRUE(d.kept().empty());
  }
  std::ofstream(target / "notes.txt") << "mine";
  fs::create_directories(target / "plots");
  std::ofstream(target / "plots" / "p.py") << "mine too";
  {
    OutputDir d(target);
    d.write("a.csv", "second a");
    d.write("b.csv", "second b");
    d.commit();
    EXPECT_EQ(d.kept(), (std::vector<std::string>{"notes.txt", "plots"}));
  }
  EXPECT_EQ(slurp(target / "a.csv"), "second a");
  EXPECT_EQ(slurp(target / "notes.txt"), "mine");
  EXPECT_EQ(slurp(target / "plots" / "p.py"), "mine too");
  EXPECT_FALSE(fs::exists(target / "stale.csv"));  // ptc's own, not written again
  // The user's files stay the user's: a third run that writes "notes.txt" keeps theirs aside.
  {
    OutputDir d(target);
    d.write("notes.txt", "ptc's notes");
    d.commit();
    EXPECT_EQ(d.kept(), (std::vector<std::string>{"notes.txt.kept", "plots"}));
  }
  EXPECT_EQ(slurp(target / "notes.txt"), "ptc's notes");
  EXPECT_EQ(slurp(target / "notes.txt.kept"), "mine");
  EXPECT_FALSE(fs::exists(target / "a.csv"));
  // Every file a run wrote is listed in its marker; the kept ones are not.
  const std::string marker = slurp(target / OutputDir::kMarker);
  EXPECT_NE(marker.find("\nnotes.txt\n"), std::string::npos) << marker;
  EXPECT_EQ(marker.find("kept"), std::string::npos) << marker;
  EXPECT_EQ(marker.find("plots"), std::string::npos) << marker;
  fs::remove_all(base);
}

// A user's file kept twice under the same name gets a free name; a directory whose marker is gone
// by the commit is not replaced; a symbolic link as --out is refused; an output never lands on
// an input (a file, a directory it is inside, the directory of a glob).
TEST(OutputDir, KeptNamesNeverCollideAndOddTargetsAreRefused) {
  const fs::path base = fs::temp_directory_path() / ("ptc_odd_" + std::to_string(::getpid()));
  fs::remove_all(base);
  const fs::path target = base / "out";
  auto run = [&](const char* name, const char* text) {
    OutputDir d(target);
    d.write(name, text);
    d.commit();
    return d.kept();
  };
  (void)run("a.csv", "ptc");
  std::ofstream(target / "b.csv") << "user 1";
  EXPECT_EQ(run("b.csv", "ptc"), std::vector<std::string>{"b.csv.kept"});
  // The next run does not write b.csv: ptc's b.csv goes, the user's b.csv.kept stays.
  EXPECT_EQ(run("a.csv", "ptc"), std::vector<std::string>{"b.csv.kept"});
  EXPECT_FALSE(fs::exists(target / "b.csv"));
  // The user adds b.csv again and a run writes b.csv: theirs becomes b.csv.kept.2, whatever the
  // order the directory lists them in, and b.csv.kept (user 1) is not overwritten.
  std::ofstream(target / "b.csv") << "user 3";
  std::ofstream(target / "c.csv") << "user 2";
  EXPECT_EQ(run("b.csv", "ptc"), (std::vector<std::string>{"b.csv.kept", "b.csv.kept.2", "c.csv"}));
  EXPECT_EQ(slurp(target / "b.csv.kept"), "user 1");
  EXPECT_EQ(slurp(target / "b.csv.kept.2"), "user 3");
  EXPECT_EQ(slurp(target / "c.csv"), "user 2");
  // The marker removed while a run works: the commit refuses and nothing is replaced.
  {
    OutputDir d(target);
    d.write("a.csv", "new");
    fs::remove(target / OutputDir::kMarker);
    EXPECT_THROW(d.commit(), InputError);
  }
  EXPECT_EQ(slurp(target / "b.csv"), "ptc");  // the last committed run's output, untouched
  EXPECT_EQ(slurp(target / "b.csv.kept"), "user 1");
  // A symbolic link as the target is refused (a rename would move the link, not the directory).
  fs::create_directory_symlink(target, base / "link");
  auto reason = [](const fs::path& p) {
    try {
      OutputDir d(p);
    } catch (const InputError& e) {
      return e.reason();
    }
    return std::string("no error");
  };
  EXPECT_EQ(reason(base / "link"), "is a symbolic link; give the directory it points to (" +
                                      fs::weakly_canonical(target).string() + ") instead");
  // A relative link names what it resolves to, not its text.
  fs::create_directory_symlink(fs::path("..") / base.filename() / target.filename(), base / "rel");
  EXPECT_EQ(reason(base / "rel"), "is a symbolic link; give the directory it points to (" +
                                     fs::weakly_canonical(target).string() + ") instead");
  fs::create_symlink(base / "nothing", base / "dangling");
  EXPECT_EQ(reason(base / "dangling"), "is a symbolic link to " + (fs::weakly_canonical(base) / "nothing").string() +
                                          ", which does not exist; give another output directory");
  // A link to a file (or to nothing) has no directory to point to.
  std::ofstream(base / "afile") << "x";
  fs::create_symlink(base / "afile", base / "flink");
  EXPECT_EQ(reason(base / "flink"), "is a symbolic link to " + fs::weakly_canonical(base / "afile").string() +
                                       ", which is not a directory; give another output directory");
  // Outputs over inputs.
  std::ofstream(base / "in.off") << "OFF";
  fs::create_directories(base / "frames");
  std::ofstream(base / "frames" / "f0.ply") << "";
  auto flag = [](const fs::path& out, const fs::path& in) {
    try {
      refuse_overwriting_input(out, in);
    } catch (const UsageError& e) {
      return e.element();
    }
    return std::string();
  };
  EXPECT_EQ(flag(base / "in.off", base / "in.off"), "--out");
  EXPECT_EQ(flag(base / "x" / ".." / "in.off", base / "in.off"), "--out");
  EXPECT_EQ(flag(base / "frames", base / "frames" / "f0.ply"), "--out");
  EXPECT_EQ(flag(base / "frames/", base / "frames" / "f0.ply"), "--out");
  EXPECT_EQ(flag(base / "frames", (base / "frames" / "*.ply").string()), "--out");
  EXPECT_EQ(flag(base / "other", base / "frames" / "f0.ply"), "");
  EXPECT_EQ(flag(base / "frames" / "sub", base / "frames"), "");  // inside an input directory: no overwrite
  EXPECT_EQ(flag(base / "in.off", "armadillo-twist"), "");  // not a path
  fs::remove_all(base);
}

}  // namespace
}  // namespace ptc

namespace ptc {
namespace {

// Errors while an output is written name the files as the user will find them, not the hidden
// temporaries being written (a full disk said ".../small/.cl.tmp-31877-0/clusters.ply").
TEST(OutputDir, ErrorsNameTheUsersPaths) {
  const std::string p = std::to_string(::getpid()), other = std::to_string(::getpid() + 1);
  EXPECT_EQ(with_user_paths("/tmp/x/small/.cl.tmp-" + p + "-0/clusters.ply: cannot write: No space left on device"),
            "/tmp/x/small/cl/clusters.ply: cannot write: No space left on device");
  EXPECT_EQ(with_user_paths(".tr.tmp-" + p + "-0/depth_0020.png: cannot write it"), "tr/depth_0020.png: cannot write it");
  EXPECT_EQ(with_user_paths("out dir/.my out.tmp-" + p + "-2/.a.csv.tmp-" + p + "-7: x"), "out dir/my out/a.csv: x");
  EXPECT_EQ(with_user_paths("cannot remove 'runs/.r1.tmp-" + p + "-3.old': busy"), "cannot remove 'runs/r1': busy");
  EXPECT_EQ(with_user_paths("d/.f.off.tmp-" + p + "-0: cannot write it"), "d/f.off: cannot write it");
  // Names that only look alike stay: another process's, a user's dated directory, other shapes,
  // and a temporary after a word with a dot (the rewrite starts at a path's start or a '/').
  for (const std::string& kept : {"a/.b.tmp-" + other + "-2/c: x", std::string("/home/u/.cache.tmp-2024-01/x: y"),
                                 "a/b.tmp-" + p + "-2/c: x", "a/.b.tmp-" + p + "-2x/c: x", std::string("nothing to see"),
                                 std::string(""), "in .x: .y.tmp-" + p + "-2/z"})
    EXPECT_EQ(with_user_paths(kept), kept);
}

}  // namespace
}  // namespace ptc

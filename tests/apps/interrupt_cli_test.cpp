// Ctrl-C on a long `ptc` run: the run stops at its next frame with exit code 130 and one line on
// stderr, and leaves no output, no temporary sibling directory and an earlier output unchanged
// (toolkit/core/cancel.h, commands/output_dir.h). The binary runs in the background
// (posix_spawn), is signalled once its temporary output directory exists, and is waited for.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_harness.h"
#include "viz/display.h"

extern char** environ;

namespace fs = std::filesystem;

namespace {

using ptc::test::lines;
using ptc::test::RunResult;
using ptc::test::slurp;
using Clock = std::chrono::steady_clock;

const std::string kData = PTC_TEST_DATA;

// The entries of `parent` that are a temporary sibling of `leaf` (OutputDir's ".LEAF.tmp-*" and
// its ".old").
std::vector<std::string> temporaries_of(const fs::path& parent, const std::string& leaf) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(parent))
    if (e.path().filename().string().starts_with("." + leaf + ".tmp-")) found.push_back(e.path().filename().string());
  return found;
}

// Every file of a directory, name -> bytes.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) files[e.path().filename().string()] = slurp(e.path());
  return files;
}

class Interrupt : public ptc::test::CliTest {
 protected:
  // Starts ptc in the background with stdout and stderr into files, SIGINT and SIGTERM at their
  // default action (whatever the test runner set), so that ptc installs its own handlers.
  pid_t start(const std::vector<std::string>& args) {
    std::vector<std::string> argv_s{PTC_BIN};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_s) argv.push_back(a.data());
    argv.push_back(nullptr);
    const std::string out = (dir_ / "stdout.txt").string(), err = (dir_ / "stderr.txt").string();
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawnattr_t at;
    posix_spawnattr_init(&at);
    sigset_t def, none;
    sigemptyset(&def);
    sigaddset(&def, SIGINT);
    sigaddset(&def, SIGTERM);
    sigemptyset(&none);
    posix_spawnattr_setsigdefault(&at, &def);
    posix_spawnattr_setsigmask(&at, &none);
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
    pid_t pid = -1;
    const int rc = posix_spawn(&pid, PTC_BIN, &fa, &at, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    EXPECT_EQ(rc, 0) << "posix_spawn " << PTC_BIN;
    return rc == 0 ? pid : -1;
  }

  // Waits until the run has started working: its temporary output directory exists (ptc has
  // installed its handlers and passed every check by then), then 1.5 s longer so that the signal
  // lands inside the frame loop (the clustering and the five builds before it take about 0.6 s).
  // False if the process ended or nothing appeared in 8 s.
  bool wait_until_working(pid_t pid, const fs::path& out) {
    const auto deadline = Clock::now() + std::chrono::seconds(8);
    while (Clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid, &status, WNOHANG) == pid) {
        exited_early_ = true;
        return false;
      }
      if (!temporaries_of(out.parent_path(), out.filename().string()).empty()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1500));
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }

  // Waits for the process to end (at most `limit`; then it is killed and the result is -1).
  RunResult wait_for(pid_t pid, std::chrono::seconds limit) {
    RunResult r;
    const auto deadline = Clock::now() + limit;
    int status = 0;
    pid_t w = 0;
    while ((w = waitpid(pid, &status, WNOHANG)) == 0 && Clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (w == 0) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      ADD_FAILURE() << "ptc did not stop within " << limit.count() << " s of the signal";
      return r;
    }
    if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) r.code = -WTERMSIG(status);
    r.out = slurp(dir_ / "stdout.txt");
    r.err = slurp(dir_ / "stderr.txt");
    return r;
  }

  // A bench run that takes far longer than the test waits (2001 frames of the 52k-triangle
  // armadillo, five configurations each: 400 frames took 31 s on two cores), so it can only end
  // early by the signal, even on a much faster machine.
  std::vector<std::string> long_bench(const fs::path& out) const {
    return {"bench", "armadillo-twist", "--data-dir", kData, "--frames", "0:2000", "--extend-frames",
            "--width", "256", "--height", "256", "--out", out.string()};
  }

  // Starts the long run, signals it once it works, and checks what every interrupted run must
  // show: exit 130, one line on stderr saying so and naming the output, no temporary sibling.
  RunResult interrupt(const fs::path& out, int sig, std::vector<std::string> args = {}) {
    const pid_t pid = start(args.empty() ? long_bench(out) : args);
    if (pid <= 0) return {};
    if (!wait_until_working(pid, out)) {
      if (!exited_early_) {  // an ended process is reaped already: its pid may be another's now
        kill(pid, SIGKILL);
        waitpid(pid, nullptr, 0);
      }
      ADD_FAILURE() << (exited_early_ ? "ptc ended before it was signalled: " + slurp(dir_ / "stderr.txt")
                                      : std::string("ptc did not start its output within 8 s"));
      return {};
    }
    EXPECT_EQ(kill(pid, sig), 0);
    const auto t0 = Clock::now();
    const RunResult r = wait_for(pid, std::chrono::seconds(8));
    // Stopping waits for the current configuration's update or trace only, not for the run.
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 5.0);
    EXPECT_EQ(r.code, 130) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("interrupted"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(out.string()), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(temporaries_of(out.parent_path(), out.filename().string()), std::vector<std::string>{});
    return r;
  }

  // A clustering of mushroom.off (ptc cluster, run once per test).
  fs::path cluster_dir() {
    const fs::path d = dir_ / "mushroom_clusters";
    const RunResult r = ptc({"cluster", kData + "/meshes/mushroom.off", "--out", d.string()});
    EXPECT_EQ(r.code, 0) << r.err;
    return d;
  }

  bool exited_early_ = false;
};

TEST_F(Interrupt, CtrlCLeavesNoOutputAndNoTemporaryDirectory) {
  const fs::path out = dir_ / "out";
  (void)interrupt(out, SIGINT);
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Interrupt, SigtermStopsTheSameWay) {
  const fs::path out = dir_ / "out";
  (void)interrupt(out, SIGTERM);
  EXPECT_FALSE(fs::exists(out));
}

// `ptc experiment` stops the same way (its study loop is the frame loop; the clusterings before it
// stop at their progress steps).
TEST_F(Interrupt, AnExperimentStopsTheSameWay) {
  const fs::path out = dir_ / "out";
  (void)interrupt(out, SIGINT,
                  {"experiment", "compare", "armadillo-twist", "--data-dir", kData, "--frames", "0:2000",
                   "--extend-frames", "--configs", "acc_growth,standard", "--width", "128", "--height", "128",
                   "--quiet", "--out", out.string()});
  EXPECT_FALSE(fs::exists(out));
}

// Xvfb servers whose parent is init (a server ptc started and left behind would be one).
std::vector<pid_t> orphan_xvfbs() {
  std::vector<pid_t> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string stat = slurp(e.path() / "stat");
    const std::size_t close = stat.rfind(')');
    if (stat.find("(Xvfb)") == std::string::npos || close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 2));
    std::string state;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid == 1) out.push_back(static_cast<pid_t>(std::stol(name)));
  }
  return out;
}

// `ptc viz` stops the same way, and the Xvfb it started goes with it.
TEST_F(Interrupt, AVizSeriesStopsAndTakesItsXvfbAlong) {
  const fs::path out = dir_ / "out";
  const std::vector<pid_t> before = orphan_xvfbs();
  (void)interrupt(out, SIGINT,
                  {"viz", "heatmap", "armadillo-twist", "--data-dir", kData, "--frames", "0:2000", "--extend-frames",
                   "--metric", "nodes_visited", "--range", "0:60", "--width", "128", "--height", "128", "--xvfb",
                   "--out", out.string()});
  EXPECT_FALSE(fs::exists(out));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  for (pid_t p : orphan_xvfbs())
    EXPECT_NE(std::find(before.begin(), before.end(), p), before.end()) << "Xvfb " << p << " was left running";
}

// An --interactive window stops too: its event loop polls the flag.
TEST_F(Interrupt, AnInteractiveWindowClosesOnSigterm) {
  ptc::viz::Display::Options xo;
  xo.force_xvfb = true;
  const ptc::viz::Display display = ptc::viz::Display::acquire(xo);  // the "user's" display: $DISPLAY for the child
  const fs::path out = dir_ / "out";
  (void)interrupt(out, SIGTERM,
                  {"viz", "partition", kData + "/meshes/mushroom.off", "--clusters", cluster_dir().string(), "--interactive",
                   "--width", "64", "--height", "64", "--out", out.string()});
  EXPECT_FALSE(fs::exists(out));
}

// An earlier complete output in the target directory is left as it was, file by file, byte for
// byte (manifest.json among them), including a file the user added.
TEST_F(Interrupt, AnEarlierOutputStaysByteIdentical) {
  const fs::path out = dir_ / "out";
  const RunResult first = ptc({"bench", "armadillo-twist", "--data-dir", kData, "--frames", "0:1", "--width", "16",
                               "--height", "16", "--out", out.string()});
  ASSERT_EQ(first.code, 0) << first.err;
  ASSERT_TRUE(fs::exists(out / "manifest.json"));
  ptc::test::spit(out / "notes.txt", "the user's notes\n");
  const std::map<std::string, std::string> before = snapshot(out);
  ASSERT_TRUE(before.count("bench.csv"));

  (void)interrupt(out, SIGINT);
  ASSERT_TRUE(fs::is_directory(out));
  const std::map<std::string, std::string> after = snapshot(out);
  for (const auto& [name, bytes] : before) {
    const auto it = after.find(name);
    ASSERT_NE(it, after.end()) << name << " is gone";
    EXPECT_EQ(it->second, bytes) << name << " changed";
  }
  for (const auto& [name, bytes] : after) EXPECT_TRUE(before.count(name)) << name << " appeared";
}

}  // namespace

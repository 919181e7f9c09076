// What the tests of the `ptc` command share: running the built binary (PTC_BIN) with arguments
// through the shell, capturing exit code, stdout and stderr; a fresh temporary directory per
// test; small files written into it; a closed cube mesh.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common/temp_dir.h"

namespace ptc::test {

namespace fs = std::filesystem;

struct RunResult {
  int code = -1;  ///< exit code, or -signal when killed by a signal
  std::string out, err;
};

/// Single-quoted for the shell.
inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

inline std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

/// A closed unit cube, 8 vertices, 12 outward-facing triangles.
inline const char* const kCube =
    "OFF\n8 12 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
    "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n3 3 7 5\n";

/// Base fixture: dir_ is a fresh directory named after the test, removed afterwards.
class CliTest : public TempDirTest {
 protected:
  RunResult ptc(const std::vector<std::string>& args) const { return run({PTC_BIN}, args); }
  /// Any program: `program` (words, quoted) followed by `args`, through the shell, with stdout
  /// and stderr captured in the test's directory.
  RunResult run(const std::vector<std::string>& program, const std::vector<std::string>& args) const {
    std::string cmd;
    for (const auto& w : program) cmd.append(cmd.empty() ? "" : " ").append(quote(w));
    for (const auto& a : args) cmd.append(" ").append(quote(a));
    const fs::path o = dir_ / "stdout.txt", e = dir_ / "stderr.txt";
    cmd.append(" >").append(quote(o.string())).append(" 2>").append(quote(e.string()));
    const int status = std::system(cmd.c_str());
    RunResult r;
    if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) r.code = -WTERMSIG(status);
    r.out = slurp(o);
    r.err = slurp(e);
    return r;
  }
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
};

}  // namespace ptc::test

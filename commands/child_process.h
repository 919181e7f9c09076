// Running a helper program (Python for the figures, jupyter nbconvert, ffmpeg) from a command:
// in its own process group (a terminal's Ctrl-C reaches ptc only, which then stops the child),
// polled so that Ctrl-C or SIGTERM to ptc stops the child at once (SIGTERM to its group, SIGKILL
// after 2 s) and the command unwinds with Interrupted. stdout and stderr go to one log file,
// read back into the result.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace ptc {

struct ChildResult {
  bool started = false;
  int code = -1;       ///< exit status; 128 + signal when it was killed
  std::string output;  ///< its stdout and stderr
};

/// argv[0] must be a path (find it first); `cwd` its working directory; `log` a scratch file
/// (removed afterwards). Throws Interrupted when the run is cancelled meanwhile.
[[nodiscard]] ChildResult run_child(const std::vector<std::string>& argv, const std::filesystem::path& cwd,
                                    const std::filesystem::path& log);

/// `name` as a path to run: as given when it contains '/' (made absolute, so that it still
/// works from another directory), else looked up in $PATH; "" when it is not an executable file.
[[nodiscard]] std::string resolve_program(const std::string& name);

}  // namespace ptc

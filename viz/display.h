// An X display for VTK's rendering (Debian's VTK 9.1 renders through GLX only: no EGL, no OSMesa,
// and it aborts the process when it cannot open a display). Nothing in viz/ creates a render
// window before a Display is alive.
//
// Display::acquire() uses the display in $DISPLAY when it answers and gives an OpenGL >= 3.2
// context (tested in a child process: indirect GLX over ssh -X or an old driver makes VTK abort
// or crash); otherwise it
// starts a private Xvfb (Debian package `xvfb`): `Xvfb -displayfd FD -noreset -nolisten tcp`, so
// that the server itself picks a free display number (no race with another Xvfb started at the
// same moment) and does not reset when its last client leaves. The server runs in its own process
// group (a Ctrl-C at the terminal reaches ptc, which stops cleanly, not the server under it) with
// PR_SET_PDEATHSIG, so it also goes when ptc is killed outright. The destructor stops it
// (SIGTERM, then SIGKILL after 2 s) and puts $DISPLAY back; the destructor runs on every way
// out of a command: success, an error, an interrupt (toolkit/core/cancel.h unwinds).
#pragma once

#include <string>
#include <sys/types.h>

namespace ptc::viz {

class Display {
 public:
  struct Options {
    bool interactive = false;  ///< a window on the user's display is wanted (no Xvfb fallback)
    bool force_xvfb = false;   ///< start a private Xvfb even when $DISPLAY answers (tests)
    std::string xvfb = "Xvfb"; ///< the server program (looked up in $PATH unless it contains '/')
    double start_timeout_s = 20;
  };

  /// The display to render on. Throws InputError (element "display") with one line saying what
  /// to do: "--interactive needs a display: ..." when interactive and $DISPLAY does not answer;
  /// "no X display is reachable ($DISPLAY is unset) and Xvfb is not installed: install the
  /// Debian package xvfb (apt-get install --no-install-recommends xvfb xauth)" when it must
  /// start Xvfb and cannot find it; "Xvfb did not start: <its last message>" when it fails.
  [[nodiscard]] static Display acquire(const Options& options);
  [[nodiscard]] static Display acquire() { return acquire(Options{}); }

  Display(Display&& other) noexcept;
  Display& operator=(Display&&) = delete;
  Display(const Display&) = delete;
  ~Display();

  /// ":N" of the display in use ($DISPLAY while this object lives).
  [[nodiscard]] const std::string& name() const { return name_; }
  /// Whether this object started the server (a private Xvfb) or found the user's display.
  [[nodiscard]] bool own_server() const { return pid_ > 0; }
  /// What was used, for manifests: "DISPLAY=:0 (the user's)" or "Xvfb :99 (started by ptc)".
  [[nodiscard]] std::string describe() const;
  /// Process id of the private Xvfb (0 when the user's display is used).
  [[nodiscard]] pid_t server_pid() const { return pid_; }

 private:
  Display() = default;
  void restore_env();
  std::string name_, previous_;  ///< previous: $DISPLAY before (empty = unset)
  std::string indirect_, note_;  ///< $LIBGL_ALWAYS_INDIRECT before; why the user's display was not used
  bool had_previous_ = false, had_indirect_ = false;
  pid_t pid_ = 0;
};

/// The path of program `name` in $PATH (or `name` itself when it contains '/' and is
/// executable); "" when there is none.
[[nodiscard]] std::string find_program(const std::string& name);

/// "" when VTK can render on display `name` (an OpenGL >= 3.2 context made current, tested in
/// a child process, since a driver that cannot may abort or crash), else why not.
[[nodiscard]] std::string gl_problem(const std::string& name);

/// Whether the X display `name` answers and offers GLX (false for "").
[[nodiscard]] bool display_usable(const std::string& name);

}  // namespace ptc::viz

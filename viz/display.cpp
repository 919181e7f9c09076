#include "viz/display.h"

#include <X11/Xlib.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "toolkit/core/error.h"

namespace ptc::viz {
namespace {

[[noreturn]] void fail(const std::string& reason) { throw InputError("", "", "display", reason); }

}  // namespace

std::string find_program(const std::string& name) {
  if (name.find('/') != std::string::npos) return access(name.c_str(), X_OK) == 0 ? name : std::string();
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    std::string dir = dirs.substr(start, end - start);
    if (dir.empty()) dir = ".";
    const std::string p = dir + "/" + name;
    if (access(p.c_str(), X_OK) == 0 && !std::filesystem::is_directory(p)) return p;
    start = end + 1;
  }
  return {};
}

namespace {

// Xlib's default handler for a lost connection calls exit(); while probing, a refused or broken
// display only makes XOpenDisplay return null, which is all we need.
int quiet_error_handler(::Display*, XErrorEvent*) { return 0; }

void stop_server(pid_t pid) {
  if (pid <= 0) return;
  kill(pid, SIGTERM);
  for (int i = 0; i < 200; ++i) {
    int status = 0;
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid || (r < 0 && errno == ECHILD)) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
}

std::string last_line(const std::string& text) {
  std::string s = text;
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  const std::size_t nl = s.rfind('\n');
  return nl == std::string::npos ? s : s.substr(nl + 1);
}

}  // namespace

bool display_usable(const std::string& name) {
  if (name.empty()) return false;
  XErrorHandler old = XSetErrorHandler(quiet_error_handler);
  ::Display* d = XOpenDisplay(name.c_str());
  bool ok = false;
  if (d) {
    int opcode = 0, event = 0, error = 0;
    ok = XQueryExtension(d, "GLX", &opcode, &event, &error) != 0;
    XCloseDisplay(d);
  }
  XSetErrorHandler(old);
  return ok;
}

Display Display::acquire(const Options& o) {
  Display d;
  const char* env = std::getenv("DISPLAY");
  d.had_previous_ = env != nullptr;
  d.previous_ = env ? env : "";
  const std::string current = env ? env : "";
  if (!o.force_xvfb && display_usable(current)) {
    d.name_ = current;
    return d;
  }
  if (o.interactive)
    fail(current.empty() ? "--interactive needs a display: $DISPLAY is unset"
                         : "--interactive needs a display: " + current + " does not answer or has no GLX");
  const std::string xvfb = find_program(o.xvfb);
  if (xvfb.empty())
    fail(std::string("no X display is reachable (") + (current.empty() ? "$DISPLAY is unset" : "$DISPLAY=" + current + " does not answer") +
         ") and Xvfb is not installed: install the Debian package xvfb (apt-get install --no-install-recommends xvfb xauth)");

  int number_pipe[2], err_pipe[2];
  if (pipe2(number_pipe, O_CLOEXEC) != 0 || pipe2(err_pipe, O_CLOEXEC) != 0)
    fail(std::string("cannot start Xvfb: pipe: ") + std::strerror(errno));
  const std::string fd_arg = std::to_string(number_pipe[1]);
  std::vector<std::string> args = {xvfb, "-displayfd", fd_arg, "-screen", "0", "1280x1024x24", "-noreset", "-nolisten", "tcp"};
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) fail(std::string("cannot start Xvfb: fork: ") + std::strerror(errno));
  if (pid == 0) {
    // Child: its own process group (a terminal's Ctrl-C is ptc's to handle), killed with ptc.
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);
    const int fd = number_pipe[1];
    fcntl(fd, F_SETFD, 0);  // the one descriptor Xvfb must keep
    dup2(err_pipe[1], STDERR_FILENO);
    const int devnull = open("/dev/null", O_RDWR);
    if (devnull >= 0) dup2(devnull, STDIN_FILENO), dup2(devnull, STDOUT_FILENO);
    signal(SIGINT, SIG_IGN);  // the process group already keeps the terminal's away
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(xvfb.c_str(), argv.data());
    _exit(127);
  }
  close(number_pipe[1]);
  close(err_pipe[1]);
  d.pid_ = pid;

  // Wait for "N\n" on the pipe (Xvfb writes it once it accepts connections), collecting its stderr.
  std::string number, errors;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<long>(o.start_timeout_s * 1000));
  bool done = false, eof_number = false;
  fcntl(err_pipe[0], F_SETFL, O_NONBLOCK);
  while (!done) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) break;
    pollfd fds[2] = {{number_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
    const int r = poll(fds, 2, static_cast<int>(std::min<long long>(left, 200)));
    if (r < 0 && errno != EINTR) break;
    char buf[512];
    if (fds[1].revents & (POLLIN | POLLHUP)) {
      const ssize_t n = read(err_pipe[0], buf, sizeof buf);
      if (n > 0 && errors.size() < 65536) errors.append(buf, static_cast<std::size_t>(n));
    }
    if (fds[0].revents & (POLLIN | POLLHUP)) {
      const ssize_t n = read(number_pipe[0], buf, sizeof buf);
      if (n > 0) number.append(buf, static_cast<std::size_t>(n));
      if (n == 0) eof_number = true;
      if (number.find('\n') != std::string::npos) done = true;
    }
    if (eof_number && !done) break;
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      d.pid_ = 0;
      break;
    }
  }
  close(number_pipe[0]);
  close(err_pipe[0]);
  if (!done) {
    stop_server(d.pid_);
    d.pid_ = 0;
    const std::string why = last_line(errors);
    fail("Xvfb did not start" + (why.empty() ? std::string(" (no message)") : ": " + why));
  }
  while (!number.empty() && (number.back() == '\n' || number.back() == ' ')) number.pop_back();
  d.name_ = ":" + number;
  setenv("DISPLAY", d.name_.c_str(), 1);
  if (!display_usable(d.name_)) {
    stop_server(d.pid_);
    d.pid_ = 0;
    d.had_previous_ ? setenv("DISPLAY", d.previous_.c_str(), 1) : unsetenv("DISPLAY");
    fail("Xvfb started on " + d.name_ + " but offers no GLX (is Debian's libgl1-mesa-dri installed?)");
  }
  return d;
}

Display::Display(Display&& other) noexcept
    : name_(std::move(other.name_)), previous_(std::move(other.previous_)), had_previous_(other.had_previous_), pid_(other.pid_) {
  other.pid_ = 0;
  other.name_.clear();
}

Display::~Display() {
  if (pid_ <= 0) return;
  stop_server(pid_);
  had_previous_ ? setenv("DISPLAY", previous_.c_str(), 1) : unsetenv("DISPLAY");
}

std::string Display::describe() const {
  return own_server() ? "Xvfb " + name_ + " (started by ptc)" : "DISPLAY=" + name_ + " (the user's)";
}

}  // namespace ptc::viz

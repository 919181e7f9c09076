#include "viz/display.h"

#include <GL/gl.h>
#include <GL/glx.h>
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
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/core/strings.h"

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
    if (dir.empty()) dir.assign(1, '.');
    std::string p = dir;  // (appended: `dir + "/" + name` trips GCC 12's -Wrestrict false positive)
    p += '/';
    p += name;
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

namespace {

// In a child process (a failing GL driver may abort or crash; VTK itself aborts when it cannot
// make a context): what VTK 9.1 needs of the display, an OpenGL >= 3.2 context made current on a
// pbuffer. Exit codes: 0 fine, 2 no display, 3 no framebuffer configuration, 4 no context,
// 5 cannot make it current, 6 version below 3.2.
[[noreturn]] void gl_probe_child(const char* name) {
  XSetErrorHandler(quiet_error_handler);
  ::Display* d = XOpenDisplay(name);
  if (!d) _exit(2);
  const int attrs[] = {GLX_DRAWABLE_TYPE, GLX_PBUFFER_BIT, GLX_RENDER_TYPE, GLX_RGBA_BIT, GLX_RED_SIZE, 8,
                       GLX_GREEN_SIZE, 8, GLX_BLUE_SIZE, 8, GLX_DEPTH_SIZE, 16, None};
  int n = 0;
  GLXFBConfig* cfg = glXChooseFBConfig(d, DefaultScreen(d), attrs, &n);
  if (!cfg || n == 0) _exit(3);
  using CreateFn = GLXContext (*)(::Display*, GLXFBConfig, GLXContext, Bool, const int*);
  const auto create = reinterpret_cast<CreateFn>(glXGetProcAddressARB(reinterpret_cast<const GLubyte*>("glXCreateContextAttribsARB")));
  GLXContext ctx = nullptr;
  if (create) {
    const int core[] = {GLX_CONTEXT_MAJOR_VERSION_ARB, 3, GLX_CONTEXT_MINOR_VERSION_ARB, 2, GLX_CONTEXT_PROFILE_MASK_ARB,
                        GLX_CONTEXT_CORE_PROFILE_BIT_ARB, None};
    ctx = create(d, cfg[0], nullptr, True, core);
  }
  if (!ctx) ctx = glXCreateNewContext(d, cfg[0], GLX_RGBA_TYPE, nullptr, True);
  if (!ctx) _exit(4);
  const int pb_attrs[] = {GLX_PBUFFER_WIDTH, 4, GLX_PBUFFER_HEIGHT, 4, None};
  const GLXPbuffer pb = glXCreatePbuffer(d, cfg[0], pb_attrs);
  if (!glXMakeContextCurrent(d, pb, pb, ctx)) _exit(5);
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  int major = 0, minor = 0;
  if (!v || std::sscanf(v, "%d.%d", &major, &minor) != 2 || major * 10 + minor < 32) _exit(6);
  _exit(0);
}

}  // namespace

std::string gl_problem(const std::string& name) {
  if (name.empty()) return "$DISPLAY is unset";
  const pid_t pid = fork();
  if (pid < 0) return std::string("cannot test the display: fork: ") + std::strerror(errno);
  if (pid == 0) gl_probe_child(name.c_str());
  int status = 0;
  bool done = false;
  for (int i = 0; i < 1500 && !done; ++i) {  // 15 s
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) done = true;
    else std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!done) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return name + " did not answer an OpenGL test within 15 s";
  }
  if (WIFSIGNALED(status)) return name + ": its OpenGL driver crashed when asked for a context (signal " + std::to_string(WTERMSIG(status)) + ")";
  switch (WIFEXITED(status) ? WEXITSTATUS(status) : -1) {
    case 0: return "";
    case 2: return name + " does not answer";
    case 3: return name + " offers no RGBA pbuffer configuration";
    case 4: return name + " gives no OpenGL context (indirect GLX?)";
    case 5: return name + ": an OpenGL context cannot be made current";
    case 6: return name + " offers OpenGL below 3.2 (VTK 9 needs 3.2)";
    default: return name + ": the OpenGL test failed";
  }
}

Display Display::acquire(const Options& o) {
  Display d;
  const char* env = std::getenv("DISPLAY");
  d.had_previous_ = env != nullptr;
  d.previous_ = env ? env : "";
  const std::string current = env ? env : "";
  if (o.interactive && o.force_xvfb) throw UsageError("--interactive", "a window needs the user's display, not --xvfb");
  std::string problem = current.empty() ? "$DISPLAY is unset" : "";
  if (!o.force_xvfb && !current.empty()) {
    problem = display_usable(current) ? gl_problem(current) : current + " does not answer or has no GLX";
    if (problem.empty()) {
      d.name_ = current;
      return d;
    }
  }
  if (o.interactive) fail("--interactive needs a display: " + problem);
  const std::string xvfb = find_program(o.xvfb);
  if (xvfb.empty())
    fail(std::string("no X display is reachable (") + (current.empty() ? "$DISPLAY is unset" : "$DISPLAY=" + current + " does not answer") +
         ") and Xvfb is not installed: install the Debian package xvfb (apt-get install --no-install-recommends xvfb xauth)");

  int number_pipe[2] = {-1, -1}, err_pipe[2] = {-1, -1};
  if (pipe2(number_pipe, O_CLOEXEC) != 0 || pipe2(err_pipe, O_CLOEXEC) != 0) {
    const int e = errno;
    for (int fd : {number_pipe[0], number_pipe[1], err_pipe[0], err_pipe[1]})
      if (fd >= 0) close(fd);
    fail(std::string("cannot start Xvfb: pipe: ") + std::strerror(e));
  }
  const std::string fd_arg = std::to_string(number_pipe[1]);
  std::vector<std::string> args = {xvfb, "-displayfd", fd_arg, "-screen", "0", "1280x1024x24", "-noreset", "-nolisten", "tcp"};
  std::vector<char*> argv;  // built before fork: the child only calls async-signal-safe functions
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    const int e = errno;
    for (int fd : {number_pipe[0], number_pipe[1], err_pipe[0], err_pipe[1]}) close(fd);
    fail(std::string("cannot start Xvfb: fork: ") + std::strerror(e));
  }
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
    execv(argv[0], argv.data());
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
    if (cancel_requested()) {
      close(number_pipe[0]);
      close(err_pipe[0]);
      stop_server(d.pid_);
      d.pid_ = 0;
      throw Interrupted();
    }
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
    const std::string why = last_nonblank_line(errors);
    fail("Xvfb did not start" + (why.empty() ? std::string(" (no message)") : ": " + why));
  }
  while (!number.empty() && (number.back() == '\n' || number.back() == ' ')) number.pop_back();
  d.name_ = ":" + number;
  setenv("DISPLAY", d.name_.c_str(), 1);
  // Mesa renders into our own Xvfb directly; an inherited request for indirect GLX would fail.
  if (const char* ind = std::getenv("LIBGL_ALWAYS_INDIRECT")) {
    d.had_indirect_ = true;
    d.indirect_ = ind;
    unsetenv("LIBGL_ALWAYS_INDIRECT");
  }
  std::string why = display_usable(d.name_) ? gl_problem(d.name_) : "it offers no GLX";
  if (!why.empty()) {
    stop_server(d.pid_);
    d.pid_ = 0;
    d.restore_env();
    fail("Xvfb started on " + d.name_ + " but cannot render: " + why + " (is Debian's libgl1-mesa-dri installed?)");
  }
  if (!problem.empty() && !current.empty()) d.note_ = "the user's display " + problem;
  return d;
}

Display::Display(Display&& other) noexcept
    : name_(std::move(other.name_)),
      previous_(std::move(other.previous_)),
      indirect_(std::move(other.indirect_)),
      note_(std::move(other.note_)),
      had_previous_(other.had_previous_),
      had_indirect_(other.had_indirect_),
      pid_(other.pid_) {
  other.pid_ = 0;
  other.name_.clear();
}

void Display::restore_env() {
  had_previous_ ? setenv("DISPLAY", previous_.c_str(), 1) : unsetenv("DISPLAY");
  if (had_indirect_) setenv("LIBGL_ALWAYS_INDIRECT", indirect_.c_str(), 1);
}

Display::~Display() {
  if (pid_ <= 0) return;
  stop_server(pid_);
  restore_env();
}

std::string Display::describe() const {
  return own_server() ? "Xvfb " + name_ + " (started by ptc" + (note_.empty() ? "" : "; " + note_) + ")"
                      : "DISPLAY=" + name_ + " (the user's)";
}

}  // namespace ptc::viz

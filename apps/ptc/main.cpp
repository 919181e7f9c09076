// The `ptc` command: parses arguments (CLI11, only in apps/ptc), calls the library, maps errors
// to exit codes: 0 success, 1 bad input or failed run (one line on stderr), 2 bad usage,
// 130 interrupted (SIGINT or SIGTERM; nothing written, a previous output intact).
// Each subcommand is registered from its own cli_<name>.cpp (see cli.h).
#include <signal.h>

#include <atomic>
#include <iostream>
#include <optional>

#include <oneapi/tbb/global_control.h>

#include "apps/ptc/cli.h"
#include "commands/errors.h"
#include "toolkit/io/mesh_io.h"

namespace {

// The first SIGINT / SIGTERM asks the run to stop at its next clean point (toolkit/core/cancel.h:
// the exception unwinds, so an uncommitted OutputDir removes its temporary directory). It also
// puts back the default action, so a second Ctrl-C stops at once (leaving a temporary sibling
// directory behind, but never a half-written output under the real name). Only async-signal-safe
// calls here: an atomic store and sigaction.
extern "C" void on_stop_signal(int) {
  ptc::request_cancel();
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(SIGINT, &dfl, nullptr);
  sigaction(SIGTERM, &dfl, nullptr);
}

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  // SA_RESTART: a write or fsync interrupted by the signal resumes instead of failing with EINTR,
  // which would report an I/O error (exit 1) instead of the interrupt.
  sa.sa_flags = SA_RESTART;
  for (int sig : {SIGINT, SIGTERM}) {
    struct sigaction old {};
    // A signal ignored on entry (a background job of a non-interactive shell, nohup) stays
    // ignored, as the shell meant.
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    sigaction(sig, &sa, nullptr);
  }
}

// What a reader tells about a file it read anyway (faces with fewer than 3 corners skipped,
// surplus PLY values): one line each on stderr, at most kMaxNotes over a run (a frame directory
// of such files would repeat the same note per frame).
void print_read_note(const std::string& file, const std::string& note) {
  constexpr int kMaxNotes = 4;
  static std::atomic<int> printed{0};
  const int n = printed.fetch_add(1);
  if (n < kMaxNotes)
    std::cerr << "ptc: note: " << file << ": " << note << "\n";
  else if (n == kMaxNotes)
    std::cerr << "ptc: note: further notes on the files read are not shown\n";
}

// "--out DIR" of the subcommand that ran, if it has one and it was given ("" otherwise).
std::string out_of(const CLI::App& cmd) {
  const CLI::Option* o = cmd.get_option_no_throw("--out");
  return o && o->count() > 0 ? o->as<std::string>() : std::string();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ptc;
  cli::Context ctx;
  ctx.args.assign(argv, argv + argc);

  CLI::App app{"ptc - precomputed triangle clusters for ray tracing animated meshes"};
  app.set_version_flag("--version", std::string("ptc ") + PTC_VERSION);
  app.require_subcommand(1);

  cli::register_info(app, ctx);
  cli::register_subdivide(app, ctx);
  cli::register_spheres(app, ctx);
  cli::register_cluster(app, ctx);
  cli::register_animate(app, ctx);
  cli::register_scenes(app, ctx);
  cli::register_trace(app, ctx);
  cli::register_bench(app, ctx);
  cli::register_experiment(app, ctx);
  cli::register_merge(app, ctx);
  cli::register_viz(app, ctx);
  cli::register_notebook(app, ctx);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "ptc: " << e.what() << " (run 'ptc --help')\n";
    return 2;
  }

  std::optional<oneapi::tbb::global_control> thread_limit;
  if (ctx.threads > 0) thread_limit.emplace(oneapi::tbb::global_control::max_allowed_parallelism, ctx.threads);

  install_stop_handlers();
  set_read_note_handler(print_read_note);
  std::string out;  // the output of the command being run, for the interrupt message
  try {
    for (const auto& c : ctx.commands)
      if (*c.app) {
        out = out_of(*c.app);
        c.run();
      }
  } catch (const Interrupted&) {
    if (out.empty())
      std::cerr << "ptc: interrupted (no output was written)\n";
    else
      std::cerr << "ptc: interrupted: nothing was written to " << out << "\n";
    return 130;  // 128 + SIGINT, what a shell reports for a Ctrl-C (also after SIGTERM)
  } catch (const UsageError& e) {
    std::cerr << "ptc: " << e.what() << " (run 'ptc --help')\n";
    return 2;
  } catch (const InputError& e) {
    std::cerr << "ptc: error: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "ptc: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "ptc: error: " << e.what() << "\n";
    return 1;
  }
  std::cout.flush();
  if (!std::cout) {
    std::cerr << "ptc: error: cannot write to stdout\n";
    return 1;
  }
  return 0;
}

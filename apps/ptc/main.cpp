// The `ptc` command: parses arguments (CLI11, only in apps/ptc), calls the library, maps errors
// to exit codes: 0 success, 1 bad input or failed run (one line on stderr), 2 bad usage,
// 130 interrupted (SIGINT or SIGTERM; nothing written, a previous output intact).
// Each subcommand is registered from its own cli_<name>.cpp (see cli.h).
#include <cerrno>
#include <cstring>
#include <iostream>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include <oneapi/tbb/global_control.h>

#include "apps/ptc/cli.h"
#include "commands/errors.h"
#include "commands/output_dir.h"
#include "commands/process.h"

namespace {

// Flushes stdout; when it cannot take the text, says so with the reason (when the failed write
// left one) and, for a run whose output `out` was committed, that the output itself is whole (a
// script that sees exit 1 should not take it for a failed run's). `code` otherwise. `earlier`:
// the errno of writes made just before (a stream already failed does not write again on flush).
int flushed_stdout(int code, const std::string& out = {}, int earlier = 0) {
  errno = 0;
  std::cout.flush();
  if (std::cout) return code;
  const int err = errno != 0 ? errno : earlier;
  std::cerr << "ptc: error: cannot write to stdout" << (err != 0 ? std::string(": ") + std::strerror(err) : "")
            << (!out.empty() && ptc::output_was_committed(out) ? " (" + out + " was written whole)" : "") << "\n";
  return 1;
}

// "--out DIR" of the subcommand that ran, if it has one and it was given ("" otherwise).
std::string out_of(const CLI::App& cmd) {
  const CLI::Option* o = cmd.get_option_no_throw("--out");
  return o && o->count() > 0 ? o->as<std::string>() : std::string();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ptc;
  open_standard_streams();     // a closed stdout must not become the next file or socket ptc opens
  use_huge_page_malloc(argv);  // before anything else: it may execute ptc again (process.h)
  install_stop_handlers();  // first: a Ctrl-C during the start-up is a request like any other
  set_memory_policy();
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

  // (Help and version text go to stdout: a stdout that cannot take them is a failure, as for
  // every other command's text.)
  // (errno is cleared first so that the reason of a write failing inside app.exit is kept.)
  const auto printed = [&app](const CLI::Error& e) {
    errno = 0;
    const int code = app.exit(e);
    return flushed_stdout(code, {}, errno);
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return printed(e);
  } catch (const CLI::CallForAllHelp& e) {
    return printed(e);
  } catch (const CLI::CallForVersion& e) {
    return printed(e);
  } catch (const CLI::ParseError& e) {
    std::string msg = e.what();
    // CLI11's words for two common slips, in the user's (the flag or command named).
    std::string names;
    bool known = false;
    for (const CLI::App* s : app.get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + s->get_name();
      known = known || (argc > 1 && s->get_name() == argv[1]);
    }
    if (argc > 1 && argv[1][0] != '-' && !known) {
      msg = std::string("'") + argv[1] + "' is not a ptc command (" + names + ")";
    } else if (const auto k = msg.find(": At Most 1 required but received"); k != std::string::npos) {
      msg = msg.substr(0, k) + ": given more than once";
    } else if (msg.find("not expected") != std::string::npos) {
      // --frame F where the command takes a range only (bench, animate, experiment): say how.
      const std::string_view command = argv[1];
      const bool ranges_only = command == "bench" || command == "animate" || command == "experiment";
      for (int i = 2; ranges_only && i < argc; ++i)
        if (std::string_view(argv[i]) == "--frame" || std::string_view(argv[i]).starts_with("--frame=")) {
          const std::string_view a = argv[i];
          const std::string f = a.size() > 7 ? std::string(a.substr(8)) : i + 1 < argc ? argv[i + 1] : "F";
          const std::string cmd =
              std::string(command) + (command == "experiment" && argv[2][0] != '-' ? std::string(" ") + argv[2] : "");
          msg = fmt::format("--frame: ptc {} takes a range of frames: --frames {}:{} for one", cmd, f, f);
          break;
        }
    }
    std::cerr << "ptc: " << msg << " (run 'ptc --help')\n";
    return 2;
  }

  std::optional<oneapi::tbb::global_control> thread_limit;
  if (ctx.threads > 0) thread_limit.emplace(oneapi::tbb::global_control::max_allowed_parallelism, ctx.threads);

  print_read_notes_on_stderr();
  std::string out, name;  // the output and name of the command being run, for the interrupt message
  try {
    for (const auto& c : ctx.commands)
      if (*c.app) {
        out = out_of(*c.app);
        name = c.app->get_name();
        if (c.app->get_parent() && c.app->get_parent()->get_parent())  // "viz heatmap"
          name = c.app->get_parent()->get_name() + " " + name;
        if (const CLI::Option* kind = c.app->get_option_no_throw("KIND"); kind && kind->count() > 0)
          name += " " + kind->as<std::string>();  // "experiment drift"
        throw_if_cancelled();  // a signal during the start-up: nothing is run
        c.run();
      }
  } catch (const Interrupted&) {
    std::cout.flush();  // what a pipe was given so far
    if (out.empty())
      std::cerr << "ptc: " << name << " interrupted (no output was written)\n";
    else
      std::cerr << "ptc: " << name << " interrupted: nothing was written to " << out << " (an earlier " << out
                << " is as it was)\n";
    return 130;  // 128 + SIGINT, what a shell reports for a Ctrl-C (also after SIGTERM)
  } catch (const UsageError& e) {
    std::cerr << "ptc: " << e.what() << " (run 'ptc --help')\n";
    return 2;
  } catch (const InputError& e) {
    std::cerr << "ptc: error: " << with_user_paths(e.what()) << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "ptc: error: " << (name.empty() ? std::string() : name + ": ")
              << "out of memory (nothing was written; 'ptc info --json MESH' estimates what a mesh needs)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "ptc: error: " << with_user_paths(e.what()) << "\n";
    return 1;
  }
  return flushed_stdout(0, out);
}

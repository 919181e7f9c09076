// The `ptc` command: parses arguments (CLI11, only in apps/ptc), calls the library, maps errors
// to exit codes: 0 success, 1 bad input or failed run (one line on stderr), 2 bad usage.
// Each subcommand is registered from its own cli_<name>.cpp (see cli.h).
#include <iostream>
#include <optional>

#include <oneapi/tbb/global_control.h>

#include "apps/ptc/cli.h"
#include "commands/errors.h"

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

  try {
    for (const auto& c : ctx.commands)
      if (*c.app) c.run();
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

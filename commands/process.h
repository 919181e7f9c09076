// What the `ptc` program sets up for its run, besides parsing (apps/ptc/main.cpp).
#pragma once

namespace ptc {

/// SIGINT and SIGTERM handlers: the first signal requests a stop at the next clean point
/// (toolkit/core/cancel.h); a second one removes the registered temporaries and ends the process
/// at once by the signal's default action. A signal ignored on entry (nohup, a background job of
/// a non-interactive shell) stays ignored.
void install_stop_handlers();

/// The notes of files read anyway (toolkit/io/mesh_io.h read_notes) go to stderr, one line each
/// ("ptc: note: FILE: ..."), at most four over a run and then one line saying so.
void print_read_notes_on_stderr();

}  // namespace ptc

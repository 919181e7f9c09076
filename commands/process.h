// What the `ptc` program sets up for its run, besides parsing (apps/ptc/main.cpp).
#pragma once

namespace ptc {

/// SIGINT and SIGTERM handlers: the first signal requests a stop at the next clean point
/// (toolkit/core/cancel.h); a second one removes the registered temporaries and ends the process
/// at once by the signal's default action. A signal ignored on entry (nohup, a background job of
/// a non-interactive shell) stays ignored.
void install_stop_handlers();

/// Memory that a long run frees is given back: glibc's malloc serves blocks of 128 KiB and more
/// with their own mappings, unmapped when freed (its default raises that threshold as the run
/// frees large blocks, after which they come from the heap, whose freed space a long-lived small
/// block can pin: `ptc trace` over 1,000 frames then grew by 100 KB a frame; bench/soak/soak.py).
void set_memory_policy();

/// The notes of files read anyway (toolkit/io/mesh_io.h read_notes) go to stderr, one line each
/// ("ptc: note: FILE: ..."), at most four over a run and then one line saying so.
void print_read_notes_on_stderr();

}  // namespace ptc

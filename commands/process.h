// What the `ptc` program sets up for its run, besides parsing (apps/ptc/main.cpp).
#pragma once

namespace ptc {

/// SIGINT and SIGTERM handlers: the first signal requests a stop at the next clean point
/// (toolkit/core/cancel.h); a second one removes the registered temporaries and ends the process
/// at once by the signal's default action. A signal ignored on entry (nohup, a background job of
/// a non-interactive shell) stays ignored.
void install_stop_handlers();

/// While one lives, a Ctrl-C or SIGTERM only requests the stop, the second one too: the handler
/// does not remove the registered temporaries at once, which an OutputDir's commit fills with the
/// user's files while it moves them into the new output. The commit looks for the request before
/// each move, undoes its moves and gives up; release() (or the end) then acts on a second
/// signal that came meanwhile as the handler would have: removes the temporaries, says so and
/// ends the process. One at a time, on the thread that runs the command.
class StopAtOnceHeld {
 public:
  StopAtOnceHeld();
  ~StopAtOnceHeld() { release(); }
  StopAtOnceHeld(const StopAtOnceHeld&) = delete;
  StopAtOnceHeld& operator=(const StopAtOnceHeld&) = delete;
  void release();

 private:
  bool held_ = false;
};

/// Opens /dev/null on each of the descriptors 0, 1 and 2 that is closed: otherwise the next file
/// ptc opens takes its number, and what it prints lands there (viz's X display connection, an
/// output file; `ptc viz ... >&-` hung in the X protocol). Call first in main.
void open_standard_streams();

/// Large blocks of glibc's malloc on transparent huge pages: glibc does it when the environment
/// variable GLIBC_TUNABLES holds glibc.malloc.hugetlb=1 at start-up, so the process sets it and
/// executes itself again, once (argv unchanged, the same process id); the new image gives the
/// user's GLIBC_TUNABLES back at once (child programs see the environment ptc was started with)
/// and records the choice (toolkit/core/memory.h malloc_huge_pages, for the manifests). Nothing
/// happens when the variable already names glibc.malloc.hugetlb (the user's choice), when
/// PTC_HUGEPAGES=0, under valgrind or an explicit ld.so invocation, when the kernel has
/// transparent huge pages off, or when the exec fails (the run goes on without).
/// Why (docs/scale.md, "Huge pages for malloc"): on the development machine 4 KiB page faults
/// cost up to 3.7 s a GiB, and `ptc cluster` at 3.3M triangles ran 23% faster with it.
/// Call first in main, before any thread or handler exists.
void use_huge_page_malloc(char** argv);

/// Memory that a long run frees is given back: glibc's malloc serves blocks of 128 KiB and more
/// with their own mappings, unmapped when freed (its default raises that threshold as the run
/// frees large blocks, after which they come from the heap, whose freed space a long-lived small
/// block can pin: `ptc trace` over 1,000 frames then grew by 100 KB a frame; bench/soak/soak.py).
void set_memory_policy();

/// The notes of files read anyway (toolkit/io/mesh_io.h read_notes) go to stderr, one line each
/// ("ptc: note: FILE: ..."), at most four over a run and then one line saying so.
void print_read_notes_on_stderr();

}  // namespace ptc

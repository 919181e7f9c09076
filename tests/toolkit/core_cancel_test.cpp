// toolkit/core/cancel.h: the process-wide stop flag that a Ctrl-C sets and the long loops poll.
#include <gtest/gtest.h>

#include <signal.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "toolkit/core/cancel.h"
#include "toolkit/io/atomic_file.h"

namespace ptc {
namespace {

// The flag is process-wide: every test starts and ends with it cleared, so that no other test of
// this program sees a stale request.
class Cancel : public ::testing::Test {
 protected:
  void SetUp() override { reset_cancel(); }
  void TearDown() override { reset_cancel(); }
};

TEST_F(Cancel, RequestSetsTheFlagUntilReset) {
  EXPECT_FALSE(cancel_requested());
  EXPECT_NO_THROW(throw_if_cancelled());
  request_cancel();
  EXPECT_TRUE(cancel_requested());
  request_cancel();  // a second request changes nothing
  EXPECT_TRUE(cancel_requested());
  // Polling does not consume the request: every loop up the stack sees it too.
  EXPECT_THROW(throw_if_cancelled(), Interrupted);
  EXPECT_TRUE(cancel_requested());
  reset_cancel();
  EXPECT_FALSE(cancel_requested());
  EXPECT_NO_THROW(throw_if_cancelled());
}

TEST_F(Cancel, InterruptedIsARuntimeErrorSayingInterrupted) {
  request_cancel();
  try {
    throw_if_cancelled();
    FAIL() << "throw_if_cancelled did not throw";
  } catch (const std::runtime_error& e) {  // what apps/ptc would map to exit 1 if caught late
    EXPECT_NE(dynamic_cast<const Interrupted*>(&e), nullptr);
    EXPECT_EQ(std::string(e.what()), "interrupted");
  }
}

// What apps/ptc does: a signal handler requests, the command's thread sees it.
extern "C" void request_on_signal(int) { request_cancel(); }

TEST_F(Cancel, ASignalHandlerAndAnotherThreadCanRequest) {
  struct sigaction sa {}, old {};
  sa.sa_handler = request_on_signal;
  sigemptyset(&sa.sa_mask);
  ASSERT_EQ(sigaction(SIGUSR1, &sa, &old), 0);
  ASSERT_EQ(raise(SIGUSR1), 0);  // delivered to this thread: the handler has run when raise returns
  EXPECT_TRUE(cancel_requested());
  ASSERT_EQ(sigaction(SIGUSR1, &old, nullptr), 0);

  reset_cancel();
  std::thread t([] { request_cancel(); });
  t.join();
  EXPECT_TRUE(cancel_requested());
}

// The registry a second signal empties: registered files and directory trees go, everything else
// (an unregistered temporary, a sibling, the parent) stays. Checked against the file system.
class Temporaries : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("ptc_temporaries_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    base_ = registered_temporaries();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  void touch(const std::filesystem::path& p) { std::ofstream(p) << "x"; }
  std::filesystem::path dir_;
  int base_ = 0;
};

TEST_F(Temporaries, RegisteredFilesAndTreesAreRemovedOthersStay) {
  namespace fs = std::filesystem;
  const fs::path file = dir_ / ".out.ply.tmp-1-0", tree = dir_ / ".out.tmp-1-1", keep = dir_ / "keep.txt",
                 unreg = dir_ / ".other.tmp-1-2";
  touch(file);
  touch(keep);
  touch(unreg);
  fs::create_directories(tree / "sub" / "deeper");
  for (int i = 0; i < 300; ++i) {  // more than one getdents buffer
    std::string name = std::to_string(i);  // (appended: a concatenation trips GCC 12's -Wrestrict)
    name.insert(0, 1, 'f');
    name += ".csv";
    touch(tree / name);
  }
  touch(tree / "sub" / "a");
  touch(tree / "sub" / "deeper" / "b");
  fs::create_symlink(keep, tree / "link");  // a link inside goes, its target stays
  const int a = register_temporary(file, false), b = register_temporary(tree, true);
  const int c = register_temporary(unreg, false);
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 0);
  ASSERT_GE(c, 0);
  EXPECT_EQ(registered_temporaries(), base_ + 3);
  unregister_temporary(c);
  EXPECT_EQ(registered_temporaries(), base_ + 2);
  remove_temporaries_now();
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(tree));
  EXPECT_TRUE(fs::exists(keep));
  EXPECT_TRUE(fs::exists(unreg));
  unregister_temporary(a);
  unregister_temporary(b);
  EXPECT_EQ(registered_temporaries(), base_);
  unregister_temporary(-1);  // ignored
}

TEST_F(Temporaries, AFullRegistrySaysSoAndSlotsAreReused) {
  std::vector<int> slots;
  for (int i = base_; i < kMaxTemporaries; ++i) {
    slots.push_back(register_temporary(dir_ / std::to_string(i), false));
    ASSERT_GE(slots.back(), 0);
  }
  EXPECT_EQ(register_temporary(dir_ / "one-too-many", false), -1);
  EXPECT_EQ(register_temporary(std::string(5000, 'a'), false), -1);  // longer than PATH_MAX
  EXPECT_EQ(register_temporary("", false), -1);
  unregister_temporary(slots.back());
  EXPECT_EQ(register_temporary(dir_ / "reused", false), slots.back());
  for (int s : slots) unregister_temporary(s);
  EXPECT_EQ(registered_temporaries(), base_);
}

// AtomicFile registers its temporary while it exists and stops writing once a stop is requested:
// the temporary goes, the target is unchanged, and nothing stays registered.
TEST_F(Temporaries, AtomicFileRegistersAndStopsOnARequest) {
  namespace fs = std::filesystem;
  reset_cancel();
  const fs::path target = dir_ / "out.txt";
  touch(target);
  {
    AtomicFile f(target);
    EXPECT_EQ(registered_temporaries(), base_ + 1);
    f.write("new");
    request_cancel();
    EXPECT_THROW(f.write("more"), Interrupted);
    EXPECT_FALSE(fs::exists(f.temp_path()));
    EXPECT_EQ(registered_temporaries(), base_);
  }
  reset_cancel();
  {
    AtomicFile f(target);
    f.write("new");
    request_cancel();
    EXPECT_THROW(f.commit(), Interrupted);  // the rename is the last chance to stop
  }
  reset_cancel();
  std::ifstream in(target);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "x");
  EXPECT_EQ(registered_temporaries(), base_);
  for (const auto& e : fs::directory_iterator(dir_)) EXPECT_EQ(e.path().filename(), "out.txt");
  {
    AtomicFile f(target);
    f.write("done");
    f.commit();
  }
  EXPECT_EQ(registered_temporaries(), base_);
}

}  // namespace
}  // namespace ptc

// toolkit/core/cancel.h: the process-wide stop flag that a Ctrl-C sets and the long loops poll.
#include <gtest/gtest.h>

#include <signal.h>

#include <stdexcept>
#include <string>
#include <thread>

#include "toolkit/core/cancel.h"

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

}  // namespace
}  // namespace ptc

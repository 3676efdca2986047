// core/system: errno texts and the guarded main of every program.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/system/errno_text.h"
#include "core/system/guarded_main.h"

namespace canalid::core {
namespace {

TEST(ErrnoText, GivesTheLibraryTextOfKnownAndUnknownValues) {
  EXPECT_EQ(ErrnoText(ENOENT), "No such file or directory");
  EXPECT_EQ(ErrnoText(EACCES), "Permission denied");
  EXPECT_EQ(ErrnoText(123456), "Unknown error 123456");
}

TEST(ErrnoText, UnknownValuesFromManyThreadsKeepTheirOwnText) {
  // POSIX does not make std::strerror thread-safe (glibc before 2.32 wrote unknown values into
  // one static buffer); ErrnoText's texts stay each thread's own.  On this glibc a smoke test.
  std::vector<std::thread> threads;
  std::vector<int> wrong(8, 0);
  for (std::size_t t = 0; t < wrong.size(); ++t) {
    threads.emplace_back([t, &wrong] {
      const int value = 200000 + static_cast<int>(t);
      for (int i = 0; i < 2000; ++i) {
        if (ErrnoText(value) != "Unknown error " + std::to_string(value)) ++wrong[t];
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (std::size_t t = 0; t < wrong.size(); ++t) EXPECT_EQ(wrong[t], 0) << "thread " << t;
}

int ReturnsThree(int, char**) { return 3; }
int ThrowsRuntimeError(int, char**) { throw std::runtime_error("boom"); }
int ThrowsInt(int, char**) { throw 7; }

TEST(GuardedMain, PassesTheBodysExitStatusThrough) {
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(GuardedMain("prog", ReturnsThree, 0, nullptr), 3);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST(GuardedMain, AnEscapedExceptionIsAnInternalErrorWithExit70) {
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(GuardedMain("prog", ThrowsRuntimeError, 0, nullptr), kExitInternalError);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "prog: internal error: boom\n");
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(GuardedMain("prog", ThrowsInt, 0, nullptr), 70);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(),
            "prog: internal error: an exception of unknown type\n");
}

}  // namespace
}  // namespace canalid::core

#include "core/system/large_buffer.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <utility>

namespace canalid::core {
namespace {

bool AlignedTo(const double* p, std::uintptr_t to) {
  return reinterpret_cast<std::uintptr_t>(p) % to == 0;
}

long MinorFaults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// The kernel's transparent huge page setting, e.g. "always [madvise] never".
std::string TransparentHugePages() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(in, line);
  return line;
}

TEST(LargeBuffer, SmallBuffersComeFromTheHeapAligned) {
  LargeBuffer b(1000);
  ASSERT_NE(b.data(), nullptr);
  EXPECT_EQ(b.size(), 1000U);
  EXPECT_FALSE(b.mapped());
  EXPECT_TRUE(AlignedTo(b.data(), 64));
  for (std::size_t i = 0; i < b.size(); ++i) b.data()[i] = static_cast<double>(i);
  EXPECT_EQ(b.data()[999], 999.0);
  EXPECT_EQ(LargeBuffer(0).data(), nullptr);
}

TEST(LargeBuffer, LargeBuffersAreMappingsAlignedToAHugePage) {
  const std::size_t count = 300000;  // 2.4 MB: two huge pages
  LargeBuffer b(count);
  ASSERT_NE(b.data(), nullptr);
  EXPECT_TRUE(b.mapped());
  EXPECT_TRUE(AlignedTo(b.data(), LargeBuffer::kHugePageBytes));
  for (std::size_t i = 0; i < count; ++i) b.data()[i] = 0.5 * static_cast<double>(i);
  double sum = 0.0;
  for (std::size_t i = 0; i < count; ++i) sum += b.data()[i];
  EXPECT_EQ(sum, 0.25 * static_cast<double>(count) * static_cast<double>(count - 1));
}

TEST(LargeBuffer, MovesHandOverTheMemory) {
  LargeBuffer a(400000);
  double* const data = a.data();
  a.data()[7] = 3.0;
  LargeBuffer b(std::move(a));
  EXPECT_EQ(a.data(), nullptr);  // NOLINT(bugprone-use-after-move): the moved-from state
  EXPECT_EQ(a.size(), 0U);
  EXPECT_EQ(b.data(), data);
  EXPECT_EQ(b.data()[7], 3.0);
  LargeBuffer c(10);
  c = std::move(b);  // c's own block is released, b's taken
  EXPECT_EQ(c.data(), data);
  EXPECT_TRUE(c.mapped());
  c = LargeBuffer();
  EXPECT_EQ(c.data(), nullptr);
}

// The point of the mapping: touching 8 MiB costs a few page faults, not 2048.  Where the kernel
// has no transparent huge pages ("never") the advice has nothing to act on: said, not passed.
TEST(LargeBuffer, TouchingALargeBufferCostsAFaultPerHugePage) {
  const std::string setting = TransparentHugePages();
  if (setting.empty() || setting.find("[never]") != std::string::npos) {
    GTEST_SKIP() << "transparent huge pages are off on this kernel ('" << setting
                 << "'): LargeBuffer's mappings use 4 KiB pages here";
  }
  const std::size_t bytes = std::size_t{8} << 20;
  LargeBuffer b(bytes / sizeof(double));
  const long before = MinorFaults();
  for (std::size_t i = 0; i < b.size(); i += 512) b.data()[i] = 1.0;  // one write per 4 KiB
  const long faults = MinorFaults() - before;
  EXPECT_LT(faults, 64) << "with 4 KiB pages: 2048; THP: " << setting;
}

}  // namespace
}  // namespace canalid::core

#pragma once
#include <cstddef>

namespace canalid::core {

/// Uninitialised doubles for record-length data (a CSV table's values, a simulated record).
/// From kHugePageBytes / 4 up, the buffer is a private anonymous mapping of its own, aligned to
/// 2 MiB, its length rounded up to 2 MiB, and advised to the kernel as transparent huge pages
/// (madvise MADV_HUGEPAGE), so that its first touch costs one page fault per 2 MiB instead of
/// one per 4 KiB (on a VM, measured: 2.4 MB touched in 0.3 ms instead of 7-9 ms; numpy advises its
/// large arrays the same way).  Where the kernel gives no huge pages (transparent_hugepage
/// "never") the mapping works as any other.  Smaller buffers come from aligned_alloc.  Either
/// way data() is 64-byte aligned.  Move-only.
class LargeBuffer final {
 public:
  /// The huge page size this class aligns to (x86-64's and arm64's with 4 KiB pages).
  static constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

  LargeBuffer() = default;
  /// @throws std::bad_alloc when the memory cannot be had.
  explicit LargeBuffer(std::size_t count);
  ~LargeBuffer();
  LargeBuffer(LargeBuffer&& other) noexcept;
  LargeBuffer& operator=(LargeBuffer&& other) noexcept;
  LargeBuffer(const LargeBuffer&) = delete;
  LargeBuffer& operator=(const LargeBuffer&) = delete;

  double* data() { return data_; }
  const double* data() const { return data_; }
  std::size_t size() const { return size_; }
  /// Whether the buffer is a mapping of its own (advised as huge pages).
  bool mapped() const { return mapped_bytes_ != 0; }

 private:
  void Release() noexcept;

  double* data_ = nullptr;
  std::size_t size_ = 0;
  std::size_t mapped_bytes_ = 0;  // 0: from aligned_alloc
};

}  // namespace canalid::core

#include "core/system/large_buffer.h"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <new>
#include <utility>

namespace canalid::core {
namespace {

constexpr std::size_t kAlignment = 64;

std::size_t RoundUp(std::size_t bytes, std::size_t to) { return (bytes + to - 1) / to * to; }

}  // namespace

LargeBuffer::LargeBuffer(std::size_t count) : size_(count) {
  if (count == 0) return;
  if (count > SIZE_MAX / sizeof(double) - kHugePageBytes) throw std::bad_alloc();
  const std::size_t bytes = count * sizeof(double);
  if (bytes < kHugePageBytes / 4) {
    data_ = static_cast<double*>(std::aligned_alloc(kAlignment, RoundUp(bytes, kAlignment)));
    if (data_ == nullptr) throw std::bad_alloc();
    return;
  }
  // A mapping one huge page longer than needed, trimmed to the aligned part: the kernel can back
  // only whole aligned 2 MiB ranges with huge pages.
  const std::size_t length = RoundUp(bytes, kHugePageBytes);
  void* raw = ::mmap(nullptr, length + kHugePageBytes, PROT_READ | PROT_WRITE,
                     MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) throw std::bad_alloc();
  char* const base = static_cast<char*>(raw);
  const auto address = reinterpret_cast<std::uintptr_t>(raw);
  const std::size_t head = RoundUp(address, kHugePageBytes) - address;
  char* const aligned = base + head;
  if (head > 0) ::munmap(base, head);
  const std::size_t tail = kHugePageBytes - head;
  if (tail > 0) ::munmap(aligned + length, tail);
  // Advice only: where the kernel has no transparent huge pages it fails and nothing changes.
  ::madvise(aligned, length, MADV_HUGEPAGE);
  data_ = reinterpret_cast<double*>(aligned);
  mapped_bytes_ = length;
}

LargeBuffer::~LargeBuffer() { Release(); }

LargeBuffer::LargeBuffer(LargeBuffer&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)),
      size_(std::exchange(other.size_, 0)),
      mapped_bytes_(std::exchange(other.mapped_bytes_, 0)) {}

LargeBuffer& LargeBuffer::operator=(LargeBuffer&& other) noexcept {
  if (this != &other) {
    Release();
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    mapped_bytes_ = std::exchange(other.mapped_bytes_, 0);
  }
  return *this;
}

void LargeBuffer::Release() noexcept {
  if (data_ == nullptr) return;
  if (mapped_bytes_ != 0) {
    ::munmap(data_, mapped_bytes_);
  } else {
    std::free(data_);
  }
  data_ = nullptr;
  size_ = 0;
  mapped_bytes_ = 0;
}

}  // namespace canalid::core

#pragma once
#include <atomic>
#include <cstddef>
#include <vector>

namespace canalid::drivers {

/// Lock-free single-producer single-consumer ring of preallocated slots. The producer fills a
/// slot in place (BeginPush/CommitPush), the consumer reads it in place (Front/Pop), so nothing is
/// allocated or copied through the ring after construction. One thread may produce and one other
/// thread may consume; the slot indices are published with release/acquire.
template <class T>
class SpscRing final {
 public:
  /// `capacity` slots, each a copy of `prototype` (give vectors their final size there).
  SpscRing(std::size_t capacity, const T& prototype) : slots_(capacity + 1, prototype) {}

  /// Producer: the free slot to fill, or nullptr when the ring is full.
  T* BeginPush() {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (Next(head) == tail_.load(std::memory_order_acquire)) return nullptr;
    return &slots_[head];
  }
  /// Producer: publishes the slot returned by the last BeginPush.
  void CommitPush() {
    head_.store(Next(head_.load(std::memory_order_relaxed)), std::memory_order_release);
  }

  /// Consumer: the oldest filled slot, or nullptr when empty.
  const T* Front() const {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return nullptr;
    return &slots_[tail];
  }
  /// Consumer: releases the slot returned by Front.
  void Pop() {
    tail_.store(Next(tail_.load(std::memory_order_relaxed)), std::memory_order_release);
  }

  std::size_t capacity() const { return slots_.size() - 1; }

 private:
  std::size_t Next(std::size_t i) const { return i + 1 == slots_.size() ? 0 : i + 1; }

  std::vector<T> slots_;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace canalid::drivers

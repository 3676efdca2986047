#include "daemon/canalidd/persistence_worker.h"

#include <exception>
#include <stdexcept>
#include <utility>

namespace canalid::daemon {

PersistenceWorker::PersistenceWorker(SaveFunction save, FailureFunction on_failure,
                                     std::size_t capacity)
    : save_(std::move(save)), on_failure_(std::move(on_failure)) {
  if (capacity == 0 || !save_ || !on_failure_)
    throw std::invalid_argument("PersistenceWorker: a capacity > 0 and both functions are needed");
  ring_.resize(capacity);
  thread_ = std::thread([this] { Run(); });
}

PersistenceWorker::~PersistenceWorker() { Stop(); }

bool PersistenceWorker::Submit(PersistedModel&& model) {
  std::unique_lock lock(mutex_);
  if (stopping_) return false;
  for (std::size_t i = 0; i < size_; ++i) {
    PersistedModel& waiting = ring_[(head_ + i) % ring_.size()];
    if (waiting.reach == model.reach && waiting.model_kind == model.model_kind) {
      waiting = std::move(model);
      ++superseded_;
      return true;
    }
  }
  room_.wait(lock, [this] { return size_ < ring_.size(); });
  ring_[(head_ + size_) % ring_.size()] = std::move(model);
  ++size_;
  lock.unlock();
  work_.notify_one();
  return true;
}

void PersistenceWorker::Stop() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  work_.notify_one();
  if (thread_.joinable()) thread_.join();
}

void PersistenceWorker::Run() {
  PersistedModel model;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      work_.wait(lock, [this] { return size_ > 0 || stopping_; });
      if (size_ == 0) return;  // stopping, and everything queued is saved
      model = std::move(ring_[head_]);
      head_ = (head_ + 1) % ring_.size();
      --size_;
    }
    room_.notify_one();
    try {
      save_(model);
      ++saved_;
    } catch (const std::exception& e) {
      ++failures_;
      on_failure_(e.what());
    } catch (...) {
      ++failures_;
      on_failure_("unknown error");
    }
  }
}

}  // namespace canalid::daemon

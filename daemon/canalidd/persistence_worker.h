#pragma once
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "daemon/canalidd/state_store.h"

namespace canalid::daemon {

/// Saves persisted models on a thread of its own, in the order they were submitted, so the sample
/// path never waits on the disk (StateStore::Save writes, fsyncs and renames: milliseconds, more
/// on a busy disk).
///
/// The queue is a ring of `capacity` slots allocated in the constructor; Submit moves the model
/// into a slot and allocates nothing.  A model submitted while an earlier one of the same reach and
/// kind still waits replaces it in its slot (it names the same file, which the later one would
/// overwrite anyway), so with capacity >= the number of reaches Submit never waits; with a full
/// ring it waits for the thread to free a slot.  Stop() (and the destructor) saves everything
/// submitted, then joins the thread: nothing submitted is lost on shutdown.  A save that throws is
/// counted and reported through `on_failure` with the exception's message, on the worker thread.
/// Submit and Stop are for one thread (the daemon's loop); the counters may be read from any.
class PersistenceWorker final {
 public:
  /// Saves one model; throws on failure (StateStore::Save).
  using SaveFunction = std::function<void(const PersistedModel&)>;
  /// Called on the worker thread with the message of a failed save (thread-safe, no throw).
  using FailureFunction = std::function<void(const std::string& what)>;

  /// Starts the thread.  @throws std::invalid_argument when capacity is 0 or a function is empty.
  PersistenceWorker(SaveFunction save, FailureFunction on_failure, std::size_t capacity);
  ~PersistenceWorker();
  PersistenceWorker(const PersistenceWorker&) = delete;
  PersistenceWorker& operator=(const PersistenceWorker&) = delete;

  /// Queues `model` (moved from) to be saved after those queued before it.  False, and nothing
  /// queued, after Stop().
  bool Submit(PersistedModel&& model);
  /// Saves what is queued, then joins the thread.  Idempotent.
  void Stop();

  int64_t saved() const { return saved_; }
  int64_t failures() const { return failures_; }
  /// Models replaced in the queue by a later one of the same reach and kind.
  int64_t superseded() const { return superseded_; }

 private:
  void Run();

  SaveFunction save_;
  FailureFunction on_failure_;
  std::vector<PersistedModel> ring_;  ///< fixed size; slots [head_, head_ + size_) wait
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  bool stopping_ = false;
  std::mutex mutex_;
  std::condition_variable work_;  ///< a model queued, or stopping
  std::condition_variable room_;  ///< a slot freed
  std::atomic<int64_t> saved_{0};
  std::atomic<int64_t> failures_{0};
  std::atomic<int64_t> superseded_{0};
  std::thread thread_;  ///< last: started once the members above exist
};

}  // namespace canalid::daemon

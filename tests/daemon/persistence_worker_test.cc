// PersistenceWorker: models are saved on its thread in the order submitted, a waiting model of
// the same reach is replaced by a newer one, Stop() saves everything queued before it returns,
// and a failing save is reported (and does not stop the saves after it).
#include "daemon/canalidd/persistence_worker.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <condition_variable>
#include <filesystem>
#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/support/run_program.h"

namespace canalid::daemon {
namespace {

using ::testing::ElementsAre;

PersistedModel Model(const std::string& reach, double area_m2) {
  PersistedModel m;
  m.reach = reach;
  m.model_kind = "id";
  m.saved_utime_us = 100;
  m.model = {{"model", "id"}, {"area_m2", area_m2}, {"delay_s", 240.0}};
  return m;
}

// Records what was saved ("reach:area"); the first save can be held until Release().
class Recorder {
 public:
  explicit Recorder(bool hold_first = false) : holding_(hold_first) {}
  void Save(const PersistedModel& m) {
    std::unique_lock lock(mutex_);
    saved_.push_back(m.reach + ":" + std::to_string(m.model["area_m2"].get<int>()));
    entered_ = true;
    changed_.notify_all();
    changed_.wait(lock, [this] { return !holding_; });
    if (m.reach == "bad") throw std::runtime_error("cannot write bad.id.json");
  }
  void Fail(const std::string& what) {
    const std::lock_guard lock(mutex_);
    failures_.push_back(what);
  }
  void WaitUntilEntered() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return entered_; });
  }
  void Release() {
    const std::lock_guard lock(mutex_);
    holding_ = false;
    changed_.notify_all();
  }
  std::vector<std::string> saved() {
    const std::lock_guard lock(mutex_);
    return saved_;
  }
  std::vector<std::string> failures() {
    const std::lock_guard lock(mutex_);
    return failures_;
  }
  PersistenceWorker::SaveFunction save() {
    return [this](const PersistedModel& m) { Save(m); };
  }
  PersistenceWorker::FailureFunction fail() {
    return [this](const std::string& what) { Fail(what); };
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  bool holding_;
  bool entered_ = false;
  std::vector<std::string> saved_;
  std::vector<std::string> failures_;
};

TEST(PersistenceWorkerTest, SavesInTheOrderSubmitted) {
  Recorder recorder;
  // Capacity 2 for 5 reaches: Submit waits for room now and then; nothing is lost or reordered.
  PersistenceWorker worker(recorder.save(), recorder.fail(), 2);
  for (int i = 1; i <= 5; ++i) EXPECT_TRUE(worker.Submit(Model("pool" + std::to_string(i), i)));
  worker.Stop();
  EXPECT_THAT(recorder.saved(), ElementsAre("pool1:1", "pool2:2", "pool3:3", "pool4:4", "pool5:5"));
  EXPECT_EQ(worker.saved(), 5);
  EXPECT_EQ(worker.failures(), 0);
  EXPECT_TRUE(recorder.failures().empty());
}

TEST(PersistenceWorkerTest, StopSavesEverythingQueued) {
  Recorder recorder(/*hold_first=*/true);
  PersistenceWorker worker(recorder.save(), recorder.fail(), 4);
  ASSERT_TRUE(worker.Submit(Model("pool1", 1)));
  recorder.WaitUntilEntered();  // pool1 is being saved; the next ones wait in the queue
  ASSERT_TRUE(worker.Submit(Model("pool2", 2)));
  ASSERT_TRUE(worker.Submit(Model("pool3", 3)));
  auto stopped = std::async(std::launch::async, [&] { worker.Stop(); });
  recorder.Release();
  stopped.get();
  EXPECT_THAT(recorder.saved(), ElementsAre("pool1:1", "pool2:2", "pool3:3"));
  EXPECT_EQ(worker.saved(), 3);
  // Stopped: nothing more is taken, and a second Stop is harmless.
  EXPECT_FALSE(worker.Submit(Model("pool4", 4)));
  worker.Stop();
  EXPECT_EQ(worker.saved(), 3);
}

TEST(PersistenceWorkerTest, ANewerModelOfAReachReplacesItsWaitingOne) {
  Recorder recorder(/*hold_first=*/true);
  PersistenceWorker worker(recorder.save(), recorder.fail(), 2);
  ASSERT_TRUE(worker.Submit(Model("pool1", 1)));
  recorder.WaitUntilEntered();
  ASSERT_TRUE(worker.Submit(Model("pool2", 2)));
  ASSERT_TRUE(worker.Submit(Model("pool3", 3)));
  // The ring is full; pool2's waiting model is replaced in its slot, so Submit does not wait.
  ASSERT_TRUE(worker.Submit(Model("pool2", 20)));
  recorder.Release();
  worker.Stop();
  EXPECT_THAT(recorder.saved(), ElementsAre("pool1:1", "pool2:20", "pool3:3"));
  EXPECT_EQ(worker.superseded(), 1);
}

TEST(PersistenceWorkerTest, AFailingSaveIsReportedAndTheNextOnesAreSaved) {
  Recorder recorder;
  PersistenceWorker worker(recorder.save(), recorder.fail(), 4);
  ASSERT_TRUE(worker.Submit(Model("pool1", 1)));
  ASSERT_TRUE(worker.Submit(Model("bad", 2)));
  ASSERT_TRUE(worker.Submit(Model("pool3", 3)));
  worker.Stop();
  EXPECT_THAT(recorder.saved(), ElementsAre("pool1:1", "bad:2", "pool3:3"));
  EXPECT_THAT(recorder.failures(), ElementsAre("cannot write bad.id.json"));
  EXPECT_EQ(worker.saved(), 2);
  EXPECT_EQ(worker.failures(), 1);
}

// As the daemon wires it: a StateStore of its own; a refused file is reported with the store's
// message, and the files saved are those LoadAll reads back.
TEST(PersistenceWorkerTest, SavesThroughAStateStore) {
  const std::filesystem::path dir = testing::TestDirectory("persistence_worker.store");
  std::vector<std::string> failures;
  {
    PersistenceWorker worker(
        [store = StateStore(dir)](const PersistedModel& m) mutable { store.Save(m); },
        [&](const std::string& what) { failures.push_back(what); }, 2);
    ASSERT_TRUE(worker.Submit(Model("pool1", 1)));
    ASSERT_TRUE(worker.Submit(Model("no/such reach", 2)));
    ASSERT_TRUE(worker.Submit(Model("pool2", 2)));
  }  // the destructor stops, after saving what is queued
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_NE(failures[0].find("no/such reach"), std::string::npos) << failures[0];
  const StateLoadReport report = StateStore(dir).LoadAll();
  EXPECT_TRUE(report.problems.empty());
  ASSERT_EQ(report.models.size(), 2u);
}

TEST(PersistenceWorkerTest, NeedsACapacityAndBothFunctions) {
  Recorder recorder;
  EXPECT_THROW(PersistenceWorker(recorder.save(), recorder.fail(), 0), std::invalid_argument);
  EXPECT_THROW(PersistenceWorker(nullptr, recorder.fail(), 1), std::invalid_argument);
  EXPECT_THROW(PersistenceWorker(recorder.save(), nullptr, 1), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::daemon

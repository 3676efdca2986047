#pragma once
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/experiment/experiment_guard.h"
#include "core/online/online_integrator_delay.h"

namespace canalid::daemon {

/// One persisted model of one reach.
// clang-tidy 14 finds a throw under nlohmann::json's noexcept move constructor (in a debug
// assertion of its invariant) and reports this struct's implicit one.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct PersistedModel {
  std::string reach;       ///< reach name from the config
  std::string model_kind;  ///< "id", "arx", ... (the "model" key of the model JSON)
  int64_t saved_utime_us = 0;
  nlohmann::json model;   ///< model JSON (drivers/json/model_json.h, docs/model-json.md)
  nlohmann::json online;  ///< the online estimator's snapshot (null if none)
};

/// What LoadAll found.
struct StateLoadReport {
  std::vector<PersistedModel> models;
  /// "PATH: reason" for each state file that was unreadable, corrupt, truncated or inconsistent
  /// (ignored; the daemon logs these and starts without that model).
  std::vector<std::string> problems;
  /// Temp files left by a write that never reached its rename (a crash); ignored.
  std::vector<std::filesystem::path> leftover_temp_files;
};

/// Models persisted in the state directory (systemd StateDirectory=, /var/lib/canalidd), one file
/// per reach and model kind: `<reach>.<model_kind>.json` holding
///   {"format": "canalid-state-v1", "reach", "model_kind", "saved_utime_us", "model", "online"}.
/// Save is atomic: the document is written to `.<file>.tmp` in the same directory, fsync'ed,
/// renamed over the target, and the directory is fsync'ed; so after a crash the file is either
/// the old one or the new one, never a mixture, and a partial write never replaces a good file.
/// Not thread-safe; blocking file I/O (call it off the sample path).
class StateStore final {
 public:
  /// @throws std::invalid_argument when `directory` is empty.
  explicit StateStore(std::filesystem::path directory);

  /// Writes one model. reach and model_kind: 1 to 64 of [A-Za-z0-9_-].
  /// @throws std::invalid_argument on a bad name; std::runtime_error naming the path and the
  ///   system error when a write, fsync or rename fails (the previous file is then unchanged).
  void Save(const PersistedModel& model);

  /// Reads every `<reach>.<model_kind>.json` state file of the directory (a missing directory is an
  /// empty state). Never throws for a bad file: it is reported in problems and skipped.
  StateLoadReport LoadAll() const;

  /// Last accepted command counter per sender (drivers::CommandAuthenticator::last_counters), saved
  /// atomically to `command-counters.json` so a restart does not reopen a replay window.
  /// @throws std::runtime_error as Save.
  void SaveCommandCounters(const std::map<std::string, int64_t, std::less<>>& counters);
  /// The saved counters; empty when there is no file. A corrupt file is reported in `problem`
  /// ("PATH: reason") and gives no counters (the timestamp window still bounds replays).
  std::map<std::string, int64_t, std::less<>> LoadCommandCounters(std::string* problem) const;

  /// The experiment guard of a reach (core/experiment/experiment_guard.h),
  /// `<reach>.experiment.json`:
  ///   {"format": "canalid-experiment-guard-v1", "reach", "actuator", "experiment",
  ///    "nominal_setpoint", "started_utime_us", "state": "running"}
  /// written atomically and durably like Save (the file and the directory entry are on disk when
  /// it returns).  @throws std::invalid_argument on a bad reach name; std::runtime_error as Save.
  void SaveGuard(const core::ExperimentGuard& guard);
  /// The guard of `reach`: kNone without a file; kCorrupt (with "PATH: reason") for a file that
  /// cannot be read, is not JSON (truncated), lacks or mistypes a key, or names another reach.
  /// Never throws for a bad file.
  core::GuardReading LoadGuard(const std::string& reach) const;
  /// Removes the guard of `reach` durably (unlink, fsync of the directory); no file is no error.
  /// @throws std::runtime_error naming the path and the system error.
  void RemoveGuard(const std::string& reach);
  std::filesystem::path GuardPath(const std::string& reach) const;

  std::filesystem::path PathFor(const std::string& reach, const std::string& model_kind) const;
  const std::filesystem::path& directory() const { return directory_; }

  /// Test hook: Save stops after writing and syncing the temp file, as if the process died
  /// before the rename.
  void set_crash_before_rename_for_test(bool crash) { crash_before_rename_ = crash; }

 private:
  void AtomicWrite(const std::filesystem::path& target, const std::string& text);
  void SyncDirectory();

  std::filesystem::path directory_;
  bool crash_before_rename_ = false;
};

}  // namespace canalid::daemon

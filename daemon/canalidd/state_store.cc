#include "daemon/canalidd/state_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/system/errno_text.h"
#include "drivers/json/model_json_read.h"

namespace canalid::daemon {
namespace {

constexpr const char* kFormat = "canalid-state-v1";
constexpr const char* kTempSuffix = ".tmp";
constexpr const char* kCountersFormat = "canalid-command-counters-v1";
constexpr const char* kCountersFile = "command-counters.json";
constexpr const char* kGuardFormat = "canalid-experiment-guard-v1";
constexpr const char* kGuardSuffix = ".experiment.json";

bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
}

[[noreturn]] void SystemFail(const std::string& what, const std::filesystem::path& path) {
  throw std::runtime_error("state store: " + what + " " + path.string() + ": " +
                           core::ErrnoText(errno));
}

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_;
};

void WriteAll(int fd, const std::string& text, const std::filesystem::path& path) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      SystemFail("cannot write", path);
    }
    done += static_cast<std::size_t>(n);
  }
}

// The JSON object of the state file `path` whose "format" is `format`, or, in `problem`, why it
// cannot be had: it cannot be opened, it is corrupt or truncated JSON, or it is not a `what`.
std::optional<nlohmann::json> ReadStateDocument(const std::filesystem::path& path,
                                                const char* format, const std::string& what,
                                                std::string& problem) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    problem = "cannot open";
    return std::nullopt;
  }
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::exception& e) {
    problem = std::string("corrupt or truncated JSON (") + e.what() + ")";
    return std::nullopt;
  }
  if (!document.is_object() || !document.contains("format") || !document["format"].is_string() ||
      document["format"].get<std::string>() != format) {
    problem = "not " + what + " (\"format\" is not \"" + format + "\")";
    return std::nullopt;
  }
  return document;
}

}  // namespace

StateStore::StateStore(std::filesystem::path directory) : directory_(std::move(directory)) {
  if (directory_.empty()) throw std::invalid_argument("state directory is empty: give a path");
}

std::filesystem::path StateStore::PathFor(const std::string& reach,
                                          const std::string& model_kind) const {
  if (model_kind == "experiment") {
    throw std::invalid_argument("state store: model kind 'experiment' names the experiment guard");
  }
  for (const auto* name : {&reach, &model_kind}) {
    if (!ValidName(*name)) {
      throw std::invalid_argument("state store: name '" + *name +
                                  "' is not 1 to 64 of [A-Za-z0-9_-]");
    }
  }
  return directory_ / (reach + "." + model_kind + ".json");
}

void StateStore::AtomicWrite(const std::filesystem::path& target, const std::string& text) {
  const std::filesystem::path temp = directory_ / ("." + target.filename().string() + kTempSuffix);
  // 0600: the state is the service's own (UMask=0077 in the unit does the same).
  Fd fd(::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600));
  if (fd.get() < 0) SystemFail("cannot create", temp);
  WriteAll(fd.get(), text, temp);
  if (::fsync(fd.get()) != 0) SystemFail("cannot fsync", temp);
  if (::close(fd.release()) != 0) SystemFail("cannot close", temp);
  if (crash_before_rename_) return;
  if (::rename(temp.c_str(), target.c_str()) != 0) SystemFail("cannot rename over", target);
  // The rename is durable only once the directory entry is on disk.
  SyncDirectory();
}

void StateStore::SyncDirectory() {
  Fd dir(::open(directory_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir.get() < 0) SystemFail("cannot open directory", directory_);
  if (::fsync(dir.get()) != 0) SystemFail("cannot fsync directory", directory_);
}

std::filesystem::path StateStore::GuardPath(const std::string& reach) const {
  if (!ValidName(reach)) {
    throw std::invalid_argument("state store: name '" + reach +
                                "' is not 1 to 64 of [A-Za-z0-9_-]");
  }
  return directory_ / (reach + kGuardSuffix);
}

void StateStore::SaveGuard(const core::ExperimentGuard& guard) {
  const std::filesystem::path target = GuardPath(guard.reach);
  nlohmann::json document = {{"format", kGuardFormat},
                             {"reach", guard.reach},
                             {"actuator", guard.actuator},
                             {"experiment", guard.experiment},
                             {"nominal_setpoint", guard.nominal_setpoint},
                             {"started_utime_us", guard.started_utime_us},
                             {"state", "running"}};
  AtomicWrite(target, document.dump(2) + "\n");
}

core::GuardReading StateStore::LoadGuard(const std::string& reach) const {
  core::GuardReading reading;
  const std::filesystem::path path = GuardPath(reach);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) && !ec) return reading;
  auto corrupt = [&](const std::string& why) {
    reading.kind = core::GuardReading::Kind::kCorrupt;
    reading.problem = path.string() + ": " + why;
    return reading;
  };
  std::string problem;
  const std::optional<nlohmann::json> document =
      ReadStateDocument(path, kGuardFormat, "an experiment guard", problem);
  if (!document) return corrupt(problem);
  try {
    core::ExperimentGuard& g = reading.guard;
    g.reach = document->at("reach").get<std::string>();
    g.actuator = document->at("actuator").get<std::string>();
    g.experiment = document->at("experiment").get<std::string>();
    g.nominal_setpoint = document->at("nominal_setpoint").get<double>();
    g.started_utime_us = document->at("started_utime_us").get<int64_t>();
  } catch (const nlohmann::json::exception& e) {
    return corrupt(std::string("missing or mistyped key (") + e.what() + ")");
  }
  if (reading.guard.reach != reach) {
    return corrupt("names reach '" + reading.guard.reach + "', not '" + reach + "'");
  }
  reading.kind = core::GuardReading::Kind::kFound;
  return reading;
}

void StateStore::RemoveGuard(const std::string& reach) {
  const std::filesystem::path path = GuardPath(reach);
  if (::unlink(path.c_str()) != 0) {
    if (errno == ENOENT) return;
    SystemFail("cannot remove", path);
  }
  SyncDirectory();
}

void StateStore::Save(const PersistedModel& model) {
  const std::filesystem::path target = PathFor(model.reach, model.model_kind);
  nlohmann::json document = {{"format", kFormat},
                             {"reach", model.reach},
                             {"model_kind", model.model_kind},
                             {"saved_utime_us", model.saved_utime_us},
                             {"model", model.model},
                             {"online", model.online}};
  AtomicWrite(target, document.dump(2) + "\n");
}

void StateStore::SaveCommandCounters(const std::map<std::string, int64_t, std::less<>>& counters) {
  nlohmann::json document = {{"format", kCountersFormat}, {"counters", nlohmann::json::object()}};
  for (const auto& [sender, counter] : counters) document["counters"][sender] = counter;
  AtomicWrite(directory_ / kCountersFile, document.dump(2) + "\n");
}

std::map<std::string, int64_t, std::less<>> StateStore::LoadCommandCounters(
    std::string* problem) const {
  std::map<std::string, int64_t, std::less<>> counters;
  const auto path = directory_ / kCountersFile;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return counters;
  std::string why;
  const std::optional<nlohmann::json> document =
      ReadStateDocument(path, kCountersFormat, "a command counter file", why);
  try {
    if (!document) throw std::runtime_error(why);
    for (const auto& [sender, counter] : document->at("counters").items()) {
      counters[sender] = counter.get<int64_t>();
    }
  } catch (const std::exception& e) {
    if (problem != nullptr) *problem = path.string() + ": " + e.what() + "; ignored";
    counters.clear();
  }
  return counters;
}

StateLoadReport StateStore::LoadAll() const {
  StateLoadReport report;
  std::error_code ec;
  if (!std::filesystem::exists(directory_, ec)) return report;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(directory_, ec)) {
    const auto name = entry.path().filename().string();
    if (name.ends_with(kTempSuffix)) {
      report.leftover_temp_files.push_back(entry.path());
    } else if (name.ends_with(".json") && !name.starts_with(".") && name != kCountersFile &&
               !name.ends_with(kGuardSuffix)) {
      files.push_back(entry.path());
    }
  }
  if (ec) {
    report.problems.push_back(directory_.string() + ": cannot list: " + ec.message());
    return report;
  }
  std::sort(files.begin(), files.end());
  for (const auto& path : files) {
    auto problem = [&](const std::string& why) {
      report.problems.push_back(path.string() + ": " + why + "; ignored");
    };
    std::string why;
    const std::optional<nlohmann::json> found =
        ReadStateDocument(path, kFormat, "a canalid state file", why);
    if (!found) {
      problem(why);
      continue;
    }
    const nlohmann::json& document = *found;
    try {
      PersistedModel model;
      model.reach = document.at("reach").get<std::string>();
      model.model_kind = document.at("model_kind").get<std::string>();
      model.saved_utime_us = document.at("saved_utime_us").get<int64_t>();
      model.model = document.at("model");
      model.online = document.at("online");
      if (!ValidName(model.reach) || !ValidName(model.model_kind) ||
          path.filename() != model.reach + "." + model.model_kind + ".json") {
        problem("reach '" + model.reach + "' and model_kind '" + model.model_kind +
                "' do not match the file name");
        continue;
      }
      if (!model.model.is_object()) {
        problem("\"model\" is not an object");
        continue;
      }
      report.models.push_back(std::move(model));
    } catch (const nlohmann::json::exception& e) {
      problem(std::string("missing or mistyped key (") + e.what() + ")");
    }
  }
  return report;
}

}  // namespace canalid::daemon

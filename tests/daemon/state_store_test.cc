// StateStore: round trip, atomic replacement, a crash between write and rename, and corrupt,
// truncated or inconsistent files, which are reported with their path and ignored; the experiment
// guard: round trip, removal, and corrupt or truncated guards reported as corrupt.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "daemon/canalidd/persisted_model_checks.h"
#include "daemon/canalidd/state_store.h"
#include "tests/support/run_program.h"

namespace canalid::daemon {
namespace {

PersistedModel Model(const std::string& reach, double area_m2, int64_t utime_us) {
  PersistedModel m;
  m.reach = reach;
  m.model_kind = "id";
  m.saved_utime_us = utime_us;
  m.model = {{"model", "id"}, {"area_m2", area_m2}, {"delay_s", 240.0}};
  m.online = {{"samples", 1200}, {"b", 0.05}, {"delay_samples", 4}};
  return m;
}

class StateStoreTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ =
      testing::TestDirectory(std::string("state_store.") +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
  StateStore store_{dir_};
};

TEST_F(StateStoreTest, RoundTripOfSeveralReaches) {
  store_.Save(Model("pool2", 34113.0, 100));
  store_.Save(Model("pool1", 6000.0, 200));
  const auto report = store_.LoadAll();
  EXPECT_TRUE(report.problems.empty());
  ASSERT_EQ(report.models.size(), 2u);
  EXPECT_EQ(report.models[0].reach, "pool1");  // sorted by file name
  EXPECT_EQ(report.models[1].reach, "pool2");
  EXPECT_EQ(report.models[1].model.at("area_m2").get<double>(), 34113.0);
  EXPECT_EQ(report.models[1].online.at("samples").get<int>(), 1200);
  EXPECT_EQ(report.models[1].saved_utime_us, 100);
  EXPECT_EQ(store_.PathFor("pool2", "id"), dir_ / "pool2.id.json");
  // Private to the service user.
  struct stat st {};
  ASSERT_EQ(::stat((dir_ / "pool2.id.json").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 077, 0u);
}

TEST_F(StateStoreTest, SaveReplacesAndLeavesNoTempFile) {
  store_.Save(Model("pool2", 30000.0, 1));
  store_.Save(Model("pool2", 34113.0, 2));
  const auto report = store_.LoadAll();
  ASSERT_EQ(report.models.size(), 1u);
  EXPECT_EQ(report.models[0].model.at("area_m2").get<double>(), 34113.0);
  EXPECT_TRUE(report.leftover_temp_files.empty());
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 1);
}

TEST_F(StateStoreTest, CrashBetweenWriteAndRenameKeepsTheOldState) {
  store_.Save(Model("pool2", 30000.0, 1));
  store_.set_crash_before_rename_for_test(true);
  store_.Save(Model("pool2", 99999.0, 2));
  // A restarted daemon: a new store over the same directory.
  const auto report = StateStore(dir_).LoadAll();
  EXPECT_TRUE(report.problems.empty());
  ASSERT_EQ(report.models.size(), 1u);
  EXPECT_EQ(report.models[0].model.at("area_m2").get<double>(), 30000.0);
  ASSERT_EQ(report.leftover_temp_files.size(), 1u);
  EXPECT_EQ(report.leftover_temp_files[0], dir_ / ".pool2.id.json.tmp");
  // The next good save replaces both.
  store_.set_crash_before_rename_for_test(false);
  store_.Save(Model("pool2", 34113.0, 3));
  const auto after = store_.LoadAll();
  ASSERT_EQ(after.models.size(), 1u);
  EXPECT_EQ(after.models[0].model.at("area_m2").get<double>(), 34113.0);
  EXPECT_TRUE(after.leftover_temp_files.empty());
}

TEST_F(StateStoreTest, TruncatedFileIsReportedWithItsPathAndIgnored) {
  store_.Save(Model("pool1", 6000.0, 1));
  store_.Save(Model("pool2", 34113.0, 1));
  const auto path = dir_ / "pool2.id.json";
  const std::string full = testing::ReadFile(path);
  // Every cut short of the whole file (the trailing newline aside) must be refused.
  for (std::size_t cut : {std::size_t{0}, std::size_t{1}, full.size() / 2, full.size() - 2}) {
    testing::WriteFile(path, full.substr(0, cut));
    const auto report = store_.LoadAll();
    ASSERT_EQ(report.models.size(), 1u) << "cut at " << cut;
    EXPECT_EQ(report.models[0].reach, "pool1");
    ASSERT_EQ(report.problems.size(), 1u);
    EXPECT_NE(report.problems[0].find(path.string()), std::string::npos) << report.problems[0];
    EXPECT_NE(report.problems[0].find("ignored"), std::string::npos);
  }
}

TEST_F(StateStoreTest, ForeignAndInconsistentFilesAreReported) {
  testing::WriteFile(dir_ / "notes.json", R"({"hello": 1})");
  testing::WriteFile(dir_ / "pool3.id.json",
                     R"({"format": "canalid-state-v1", "reach": "pool9", "model_kind": "id",
                         "saved_utime_us": 1, "model": {}, "online": null})");
  testing::WriteFile(dir_ / "pool4.id.json",
                     R"({"format": "canalid-state-v1", "reach": "pool4", "model_kind": "id",
                         "saved_utime_us": "yesterday", "model": {}, "online": null})");
  testing::WriteFile(dir_ / "README", "not json, not a state file");
  const auto report = store_.LoadAll();
  EXPECT_TRUE(report.models.empty());
  ASSERT_EQ(report.problems.size(), 3u);
  EXPECT_NE(report.problems[0].find("notes.json"), std::string::npos);
  EXPECT_NE(report.problems[1].find("pool3.id.json"), std::string::npos);
  EXPECT_NE(report.problems[1].find("do not match"), std::string::npos);
  EXPECT_NE(report.problems[2].find("pool4.id.json"), std::string::npos);
}

TEST_F(StateStoreTest, MissingDirectoryIsAnEmptyState) {
  const auto report = StateStore(dir_ / "absent").LoadAll();
  EXPECT_TRUE(report.models.empty());
  EXPECT_TRUE(report.problems.empty());
}

TEST_F(StateStoreTest, BadNamesAndUnwritableDirectory) {
  EXPECT_THROW(store_.Save(Model("../etc", 1.0, 1)), std::invalid_argument);
  EXPECT_THROW(store_.Save(Model("", 1.0, 1)), std::invalid_argument);
  EXPECT_THROW(StateStore(""), std::invalid_argument);
  StateStore missing(dir_ / "absent");
  try {
    missing.Save(Model("pool2", 1.0, 1));
    ADD_FAILURE() << "saved into a missing directory";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("absent"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace canalid::daemon

namespace canalid::daemon {
namespace {

TEST(StateStoreCounters, RoundTripAndCorruption) {
  const auto dir =
      testing::TestDirectory(std::string("state_store_counters.") +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
  StateStore store(dir);
  std::string problem;
  EXPECT_TRUE(store.LoadCommandCounters(&problem).empty());
  EXPECT_TRUE(problem.empty());
  // Counters near 2^63 survive JSON (nlohmann keeps int64 exact).
  store.SaveCommandCounters({{"ops1", 41}, {"operator@scada", 1763700000000000123}});
  const auto loaded = store.LoadCommandCounters(&problem);
  EXPECT_TRUE(problem.empty());
  ASSERT_EQ(loaded.size(), 2u);
  EXPECT_EQ(loaded.at("ops1"), 41);
  EXPECT_EQ(loaded.at("operator@scada"), 1763700000000000123);
  // Not mistaken for a model file.
  EXPECT_TRUE(store.LoadAll().problems.empty());

  const auto path = dir / "command-counters.json";
  const std::string full = testing::ReadFile(path);
  testing::WriteFile(path, full.substr(0, full.size() / 2));
  EXPECT_TRUE(store.LoadCommandCounters(&problem).empty());
  EXPECT_NE(problem.find(path.string()), std::string::npos) << problem;
}

core::ExperimentGuard Guard() {
  core::ExperimentGuard g;
  g.reach = "pool2";
  g.actuator = "gate1_setpoint";
  g.experiment = "pool2_prbs";
  g.nominal_setpoint = 1.532637354;
  g.started_utime_us = 1763700000123456;
  return g;
}

TEST(StateStoreGuard, RoundTripRemoveAndNotAModel) {
  const auto dir =
      testing::TestDirectory(std::string("state_store_guard.") +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
  StateStore store(dir);
  EXPECT_EQ(store.LoadGuard("pool2").kind, core::GuardReading::Kind::kNone);
  store.SaveGuard(Guard());
  EXPECT_EQ(store.GuardPath("pool2"), dir / "pool2.experiment.json");
  const core::GuardReading r = store.LoadGuard("pool2");
  ASSERT_EQ(r.kind, core::GuardReading::Kind::kFound) << r.problem;
  EXPECT_EQ(r.guard.reach, "pool2");
  EXPECT_EQ(r.guard.actuator, "gate1_setpoint");
  EXPECT_EQ(r.guard.experiment, "pool2_prbs");
  EXPECT_EQ(r.guard.nominal_setpoint, 1.532637354);  // exact: JSON keeps every digit
  EXPECT_EQ(r.guard.started_utime_us, 1763700000123456);
  // Neither a model nor a problem for LoadAll, and no model kind may take its name.
  const StateLoadReport report = store.LoadAll();
  EXPECT_TRUE(report.models.empty());
  EXPECT_TRUE(report.problems.empty());
  EXPECT_THROW(store.PathFor("pool2", "experiment"), std::invalid_argument);
  store.RemoveGuard("pool2");
  EXPECT_FALSE(std::filesystem::exists(dir / "pool2.experiment.json"));
  EXPECT_EQ(store.LoadGuard("pool2").kind, core::GuardReading::Kind::kNone);
  store.RemoveGuard("pool2");  // none: no error
}

TEST(StateStoreGuard, CorruptTruncatedOrInconsistentGuardsAreReportedAsCorrupt) {
  const auto dir =
      testing::TestDirectory(std::string("state_store_guard.") +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
  StateStore store(dir);
  store.SaveGuard(Guard());
  const auto path = dir / "pool2.experiment.json";
  const std::string full = testing::ReadFile(path);
  auto expect_corrupt = [&](const std::string& text, const std::string& why) {
    testing::WriteFile(path, text);
    const core::GuardReading r = store.LoadGuard("pool2");
    EXPECT_EQ(r.kind, core::GuardReading::Kind::kCorrupt) << why;
    EXPECT_NE(r.problem.find(path.string()), std::string::npos) << why << ": " << r.problem;
  };
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, full.size() / 2, full.size() - 3})
    expect_corrupt(full.substr(0, n), "truncated to " + std::to_string(n) + " bytes");
  expect_corrupt(std::string(64, '\0'), "zeros (a block never written)");
  expect_corrupt("[1, 2]", "not an object");
  std::string no_nominal = full;
  no_nominal.replace(no_nominal.find("nominal_setpoint"), 16, "nominal");
  expect_corrupt(no_nominal, "no nominal_setpoint");
  std::string text_nominal = full;
  text_nominal.replace(text_nominal.find("1.532637354"), 11, "\"1.53\"");
  expect_corrupt(text_nominal, "a nominal that is text");
  std::string other_reach = full;
  other_reach.replace(other_reach.find("\"pool2\""), 7, "\"pool3\"");
  expect_corrupt(other_reach, "names another reach");
  std::string other_format = full;
  other_format.replace(other_format.find("canalid-experiment-guard-v1"), 27, "canalid-state-v1");
  expect_corrupt(other_format, "another format");
}

// The reach's bank: Ts 60 s, delays 0..30 samples.
core::OnlineIntegratorDelayOptions Bank() {
  core::OnlineIntegratorDelayOptions o;
  o.sample_time_s = 60.0;
  o.min_delay_samples = 0;
  o.max_delay_samples = 30;
  return o;
}

// A state file written by hand, as an operator or an older build might leave it.
PersistedModel LoadOne(const std::filesystem::path& dir, const std::string& model_json) {
  testing::WriteFile(dir / "pool2.id.json",
                     R"({"format": "canalid-state-v1", "reach": "pool2", "model_kind": "id",
                         "saved_utime_us": 1, "online": null, "model": )" +
                         model_json + "}\n");
  const StateLoadReport report = StateStore(dir).LoadAll();
  EXPECT_EQ(report.models.size(), 1u);
  return report.models.empty() ? PersistedModel{} : report.models[0];
}

TEST_F(StateStoreTest, ReloadedModelsAreValidatedLikeAnyInput) {
  const core::OnlineIntegratorDelayOptions bank = Bank();
  // A good one: A = 60 / 0.00175886 = 34113 m2, nk 11.
  const std::string good =
      R"({"model": "id", "b": 0.00175886, "nk": 11, "sample_time_s": 60.0, "delay_s": 660.0,
          "area_m2": 34112.98})";
  EXPECT_EQ(PersistedIntegratorDelayProblem(LoadOne(dir_, good), bank), "");
  const struct {
    const char* json;
    const char* problem;
  } bad[] = {
      {R"({"model": "id", "b": -0.000450812, "nk": 11, "sample_time_s": 60.0, "area_m2": -133093})",
       "area_m2 -133093 is not > 0 and finite"},
      {R"({"model": "id", "b": 0.00175886, "nk": 11, "sample_time_s": 60.0, "delay_s": 1e300})",
       "delay_s 1e+300 is not nk x sample_time_s = 660"},
      {R"({"model": "id", "b": 0.00175886, "nk": 1e300, "sample_time_s": 60.0})", "key 'nk'"},
      // nlohmann writes NaN as null.
      {R"({"model": "id", "b": null, "nk": 11, "sample_time_s": 60.0})", "key 'b'"},
      {R"({"model": "id", "b": 0.00175886, "nk": 11, "sample_time_s": 60.0, "area_m2": null})",
       "area_m2 null is not sample_time_s / b"},
      {R"({"model": "id", "b": 0.00175886, "nk": 11, "sample_time_s": 10.0})",
       "sample_time_s 10.0 is not the reach's 60 s"},
      {R"({"model": "id", "b": 0.00175886, "nk": 11})", "sample_time_s none is not the reach's"},
      {R"({"model": "id", "b": 0.00175886, "nk": 30, "sample_time_s": 60.0})",
       "delay 30 samples is at the edge of the bank [0, 30]"},
      {R"({"model": "id", "b": 0.00175886, "nk": 31, "sample_time_s": 60.0})",
       "delay 31 samples is outside the bank [0, 30]"},
      {R"({"model": "foptd", "gain": 1, "time_constant_s": 10, "delay_s": 0})", "key 'model'"},
  };
  for (const auto& c : bad) {
    const std::string problem = PersistedIntegratorDelayProblem(LoadOne(dir_, c.json), bank);
    EXPECT_NE(problem.find(c.problem), std::string::npos) << c.json << "\n -> " << problem;
  }
  PersistedModel arx = LoadOne(dir_, good);
  arx.model_kind = "arx";
  EXPECT_NE(PersistedIntegratorDelayProblem(arx, bank), "");
}

// An idz model is read back with its own reader and the same checks as an id model.
TEST_F(StateStoreTest, ReloadedIdzModelsAreValidatedLikeIdModels) {
  const core::OnlineIntegratorDelayOptions bank = Bank();
  auto idz = [&](const std::string& json) {
    PersistedModel m = LoadOne(dir_, json);
    m.model_kind = "idz";
    return PersistedModelProblem(m, bank);
  };
  EXPECT_EQ(idz(R"({"model": "idz", "b": 0.00175886, "nk": 11, "sample_time_s": 60.0,
                   "delay_s": 660.0, "area_m2": 34112.98, "p21_s_per_m2": 0.0185,
                   "p22_s_per_m2": 0.0133})"),
            "");
  EXPECT_NE(idz(R"({"model": "idz", "b": 0.00175886, "nk": 31, "sample_time_s": 60.0})")
                .find("delay 31 samples is outside the bank [0, 30]"),
            std::string::npos);
  EXPECT_NE(idz(R"({"model": "idz", "b": 0.00175886, "nk": 11, "sample_time_s": 60.0,
                   "p22_s_per_m2": "x"})")
                .find("p22_s_per_m2"),
            std::string::npos);
  // An id model's file under the idz kind is refused by the idz reader.
  EXPECT_NE(idz(R"({"model": "id", "b": 0.00175886, "nk": 11, "sample_time_s": 60.0})")
                .find("key 'model'"),
            std::string::npos);
}

}  // namespace
}  // namespace canalid::daemon

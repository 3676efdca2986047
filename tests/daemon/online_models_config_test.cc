// The reach keys of the online model registry, read from TOML as canalidd reads them: each key
// changes what the reach runs (the estimators built, their orders, grid, delays and input
// channels), and bad values name their key.  The estimators themselves are checked in
// tests/core/online_model_test.cc.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "core/reach/reach_controller.h"
#include "daemon/config/config_loader.h"
#include "daemon/config/plan_from_config.h"

namespace canalid::daemon {
namespace {

using ::testing::HasSubstr;

// One PLC polled every 0.1 s at time scale 600 (Ts = 60 plant s), a reach with every channel a
// process model can read; `reach_keys` are appended to its table.
std::string Config(const std::string& reach_keys) {
  std::string text = R"([daemon]
time_scale = 600.0

[[plc]]
name = "p"
host = "127.0.0.1"
poll_period_s = 0.1
response_timeout_s = 0.05
)";
  const char* channels[][3] = {{"q_in", "flow", "input"},     {"q_out", "flow", "input"},
                               {"level", "level", "input"},   {"gate", "gate", "holding"},
                               {"gate_pos", "gate", "input"}, {"level_up", "level", "input"}};
  int address = 0;
  for (const auto& ch : channels) {
    text += "\n[[channel]]\nname = \"" + std::string(ch[0]) + "\"\nplc = \"p\"\nrole = \"" + ch[1] +
            "\"\nregister = \"" + ch[2] + "\"\naddress = " + std::to_string(address) +
            "\ntype = \"f32\"\n";
    if (std::string(ch[0]) == "gate") {
      text += "writable = true\nsetpoint_min = 0.0\nsetpoint_max = 2.0\nmax_rate_per_s = 1.0\n";
    }
    address += 2;
  }
  text += R"(
[[reach]]
name = "pool2"
inflow = "q_in"
outflow = "q_out"
level = "level"
actuator = "gate"
nominal_inflow_m3s = 10.0
expected_delay_s = 600.0
level_min_m = 1.0
level_max_m = 3.0
max_delay_s = 1200.0
)" + reach_keys;
  return text;
}

// The reach as canalidd builds it: channels are indexed in the order above.
core::ReachControllerOptions Build(const std::string& reach_keys) {
  const auto config =
      std::make_shared<const config::DaemonConfig>(ParseDaemonConfig(Config(reach_keys), "t.toml"));
  const std::vector<std::string> order = {"q_in", "q_out", "level", "gate", "gate_pos", "level_up"};
  return config::BuildReachControllerOptions(config, config->reaches[0], [&](const std::string& c) {
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (order[i] == c) return static_cast<int>(i);
    }
    throw std::invalid_argument("not polled: " + c);
  });
}

std::vector<std::string> Issues(const std::string& reach_keys) {
  try {
    ParseDaemonConfig(Config(reach_keys), "t.toml");
  } catch (const ConfigError& e) {
    std::vector<std::string> out;
    for (const ConfigIssue& issue : e.issues()) out.push_back(issue.ToString());
    return out;
  }
  return {};
}

std::vector<core::OnlineModelKind> Kinds(const core::ReachController& reach) {
  std::vector<core::OnlineModelKind> kinds;
  for (const auto& model : reach.pipeline().online_models()) kinds.push_back(model->kind());
  return kinds;
}

TEST(OnlineModelsConfig, OnlineModelsBuildEveryListedKindInOrderAndNothingElse) {
  using K = core::OnlineModelKind;
  EXPECT_EQ(Kinds(core::ReachController(Build(""))), (std::vector<K>{K::kIntegratorDelay}));
  EXPECT_EQ(Kinds(core::ReachController(Build("online_models = []\n"))), std::vector<K>{});
  EXPECT_EQ(Kinds(core::ReachController(
                Build("online_models = [\"frac-foptd\", \"id\", \"arx\", \"lpv\"]\n"
                      "lpv_scheduling = \"level_up\"\n"))),
            (std::vector<K>{K::kIntegratorDelay, K::kFractionalFoptd, K::kArx, K::kLpvArx}));
  EXPECT_EQ(Kinds(core::ReachController(Build("online_models = [\"arx\"]\n"))),
            (std::vector<K>{K::kArx}));
}

TEST(OnlineModelsConfig, OrdersGridAndDelaysReachTheEstimators) {
  const core::ReachControllerOptions defaults =
      Build("online_models = [\"arx\", \"frac-foptd\", \"lpv\"]\nlpv_scheduling = \"level_up\"\n");
  const auto& d = defaults.pipeline.process_models;
  ASSERT_EQ(d.size(), 3U);
  EXPECT_EQ(d[0].arx.na, 2);
  EXPECT_EQ(d[0].arx.nb, 2);
  EXPECT_EQ(d[0].arx.max_delay_samples, 20);  // 1200 s / 60 s
  // Without initial_covariance every kind starts from the P0 `canalid identify --online`
  // defaults to: 1e10.
  EXPECT_EQ(defaults.pipeline.online_id.rls.initial_covariance, 1e10);
  EXPECT_EQ(d[0].arx.rls.initial_covariance, 1e10);
  EXPECT_EQ(d[1].fractional.rls.initial_covariance, 1e10);
  EXPECT_EQ(d[2].lpv.rls.initial_covariance, 1e10);
  EXPECT_EQ(d[1].fractional.alphas.size(), 8U);
  EXPECT_EQ(d[1].fractional.delay_samples, 10);  // expected_delay_s 600 s
  EXPECT_EQ(d[2].lpv.na, 1);
  EXPECT_EQ(d[2].lpv.delay_samples, 10);

  const core::ReachControllerOptions set = Build(
      "online_models = [\"arx\", \"frac-foptd\", \"lpv\"]\nlpv_scheduling = \"level_up\"\n"
      "arx_na = 1\narx_nb = 3\nfractional_alphas = [0.7, 0.9]\nfractional_delay_s = 125.0\n"
      "lpv_na = 2\nlpv_nb = 2\nlpv_delay_s = 0.0\nmin_delay_s = 120.0\n");
  const auto& s = set.pipeline.process_models;
  EXPECT_EQ(s[0].arx.na, 1);
  EXPECT_EQ(s[0].arx.nb, 3);
  EXPECT_EQ(s[0].arx.min_delay_samples, 2);
  EXPECT_EQ(s[1].fractional.alphas, (std::vector<double>{0.7, 0.9}));
  EXPECT_EQ(s[1].fractional.delay_samples, 2);  // 125 / 60 = 2.08
  EXPECT_EQ(s[2].lpv.na, 2);
  EXPECT_EQ(s[2].lpv.nb, 2);
  EXPECT_EQ(s[2].lpv.delay_samples, 0);
}

// initial_covariance: P0 of every online kind of the reach, in (0, 1e20].
TEST(OnlineModelsConfig, InitialCovarianceReachesEveryEstimator) {
  const core::ReachControllerOptions set = Build(
      "online_models = [\"id\", \"arx\", \"frac-foptd\", \"lpv\", \"idz\", \"frac-ss\"]\n"
      "lpv_scheduling = \"level_up\"\ninitial_covariance = 0.25\n");
  EXPECT_EQ(set.pipeline.online_id.rls.initial_covariance, 0.25);
  const auto& m = set.pipeline.process_models;
  ASSERT_EQ(m.size(), 5U);  // every kind but id, which is online_id
  EXPECT_EQ(m[0].arx.rls.initial_covariance, 0.25);
  EXPECT_EQ(m[1].fractional.rls.initial_covariance, 0.25);
  EXPECT_EQ(m[2].lpv.rls.initial_covariance, 0.25);
  EXPECT_EQ(m[3].id.rls.initial_covariance, 0.25);
  EXPECT_EQ(m[4].frac_ss.rls.initial_covariance, 0.25);
  for (const char* bad : {"0.0", "-1.0", "1e21", "nan"}) {
    EXPECT_THAT(Issues(std::string("initial_covariance = ") + bad + "\n"),
                ::testing::Contains(HasSubstr("reach[0].initial_covariance")))
        << bad;
  }
}

// frac-ss: frac_ss_q sets the online model's and the batch fit's order, frac_ss_delay_s the
// online model's known delay (default expected_delay_s); q is one of the CLI's 1, 2, 4.
TEST(OnlineModelsConfig, FracSsKeysReachTheOnlineModelAndTheBatchFit) {
  const core::ReachControllerOptions defaults =
      Build("online_models = [\"frac-ss\"]\nbatch_models = [\"frac-ss\"]\n");
  ASSERT_EQ(defaults.pipeline.process_models.size(), 1U);
  const core::OnlineModelOptions& d = defaults.pipeline.process_models[0];
  EXPECT_EQ(d.kind, core::OnlineModelKind::kFracSs);
  EXPECT_EQ(d.frac_ss.q, 2);
  EXPECT_EQ(d.frac_ss.delay_samples, 10);  // expected_delay_s 600 s
  EXPECT_EQ(defaults.pipeline.batch_process_models,
            std::vector<core::ProcessBatchKind>{core::ProcessBatchKind::kFracSs});
  EXPECT_EQ(defaults.pipeline.batch_process.frac_ss_q, 2);
  const core::ReachControllerOptions set = Build(
      "online_models = [\"frac-ss\"]\nbatch_models = [\"frac-ss\"]\nfrac_ss_q = 4\n"
      "frac_ss_delay_s = 185.0\n");
  EXPECT_EQ(set.pipeline.process_models[0].frac_ss.q, 4);
  EXPECT_EQ(set.pipeline.process_models[0].frac_ss.delay_samples, 3);  // 185 / 60 = 3.08
  EXPECT_EQ(set.pipeline.batch_process.frac_ss_q, 4);
  const core::ReachController reach(set);
  ASSERT_EQ(Kinds(reach), std::vector<core::OnlineModelKind>{core::OnlineModelKind::kFracSs});
  core::OnlineModelSnapshot snapshot;
  reach.pipeline().online_models()[0]->FillSnapshot(snapshot);
  EXPECT_EQ(snapshot.num_params, 2 + 8 + 7 + 2);  // delay, alpha, a1..a8, c1..c7, rest point
  EXPECT_EQ(snapshot.Value("alpha"), 0.25);
  EXPECT_EQ(snapshot.Value("delay_s"), 180.0);

  EXPECT_THAT(Issues("frac_ss_q = 3\n"),
              ::testing::Contains(HasSubstr("reach[0].frac_ss_q: 3 is out of range (allowed: 1, "
                                            "2 or 4)")));
  EXPECT_THAT(Issues("online_models = [\"frac-ss\"]\nfrac_ss_delay_s = -1.0\n"),
              ::testing::Contains(HasSubstr("reach[0].frac_ss_delay_s")));
}

// The input of the process models: the actuator's reading, or actuator_position's; lpv's
// scheduling variable from lpv_scheduling.  Seen in the operating points the models take from
// the first poll.
// id_wave_front: the online id bank's p21 term, on by default as in the batch fit and the CLI.
TEST(OnlineModelsConfig, IdWaveFrontSwitchesTheBanksP21Term) {
  // The parameter names the daemon publishes for its online id model.
  auto names = [](const std::string& toml) {
    const core::ReachController reach(Build(toml));
    core::OnlineModelSnapshot snapshot;
    reach.pipeline().online_models().front()->FillSnapshot(snapshot);
    return std::vector<std::string>(snapshot.names.begin(), snapshot.names.end());
  };
  EXPECT_TRUE(Build("").pipeline.online_id.wave_front_term);
  EXPECT_TRUE(Build("").pipeline.online_id.wave_front_non_negative);
  EXPECT_THAT(names(""), ::testing::Contains("p21_s_per_m2"));
  EXPECT_FALSE(Build("id_wave_front = false\n").pipeline.online_id.wave_front_term);
  EXPECT_THAT(names("id_wave_front = false\n"),
              ::testing::Not(::testing::Contains("p21_s_per_m2")));
  EXPECT_EQ(names("").size(), names("id_wave_front = false\n").size() + 1);
  EXPECT_THAT(Issues("online_models = [\"arx\"]\nid_wave_front = false\n"),
              ::testing::Contains(
                  HasSubstr("reach[0].id_wave_front: has no effect: online_models has no \"id\"")));
}

TEST(OnlineModelsConfig, ActuatorPositionAndSchedulingChannelsFeedTheProcessModels) {
  auto first_operating_point = [](const std::string& keys) {
    core::ReachController reach(Build(keys));
    // Channel values: q_in, q_out, level, gate setpoint, gate position, upstream level.
    const std::vector<double> values = {10.0, 9.0, 2.1, 0.6, 0.55, 2.4};
    const core::ReachReadings r = core::ReadReach(
        reach.options().channels, values, [](std::size_t) { return true; }, true, true, 0.0);
    reach.OnPoll(r);
    core::OnlineModelSnapshot s;
    reach.pipeline().online_models().back()->FillSnapshot(s);
    return s.Value("input_operating_point");
  };
  EXPECT_EQ(first_operating_point("online_models = [\"arx\"]\n"), 0.6);
  EXPECT_EQ(first_operating_point("online_models = [\"arx\"]\nactuator_position = \"gate_pos\"\n"),
            0.55);
  const core::ReachControllerOptions lpv =
      Build("online_models = [\"lpv\"]\nlpv_scheduling = \"level_up\"\n");
  EXPECT_EQ(lpv.channels.scheduling, 5);
  EXPECT_EQ(lpv.channels.actuator_position, -1);
}

TEST(OnlineModelsConfig, BadValuesNameTheirKey) {
  EXPECT_THAT(
      Issues("online_models = [\"lpv\"]\n"),
      ::testing::Contains(HasSubstr("reach[0].lpv_scheduling: missing (required with online "
                                    "model \"lpv\")")));
  EXPECT_THAT(Issues("online_models = [\"frac\"]\n"),
              ::testing::Contains(HasSubstr("\"frac\" is not allowed (allowed: id, arx, "
                                            "frac-foptd, lpv, idz, frac-ss)")));
  EXPECT_THAT(Issues("arx_na = 10\narx_nb = 7\n"),
              ::testing::Contains(HasSubstr("reach[0].arx_nb: 7 is out of range")));
  EXPECT_THAT(Issues("arx_nb = 0\n"), ::testing::Contains(HasSubstr("reach[0].arx_nb")));
  EXPECT_THAT(Issues("fractional_alphas = []\n"),
              ::testing::Contains(HasSubstr("reach[0].fractional_alphas")));
  EXPECT_THAT(Issues("fractional_alphas = [0.5, 2.0]\n"),
              ::testing::Contains(HasSubstr("reach[0].fractional_alphas[1]")));
  EXPECT_THAT(Issues("fractional_alphas = [0.5, \"x\"]\n"),
              ::testing::Contains(HasSubstr("reach[0].fractional_alphas[1]: expected a number")));
  EXPECT_THAT(Issues("online_models = [\"frac-foptd\"]\nfractional_delay_s = -1.0\n"),
              ::testing::Contains(HasSubstr("reach[0].fractional_delay_s")));
  EXPECT_THAT(Issues("online_models = [\"lpv\"]\nlpv_scheduling = \"level_up\"\n"
                     "lpv_delay_s = 1e9\n"),
              ::testing::Contains(HasSubstr("reach[0].lpv_delay_s")));
  // The delays of kinds the reach does not run are not held against its bank (their defaults
  // follow expected_delay_s, which may exceed 2000 samples).
  EXPECT_TRUE(Issues("fractional_delay_s = 1e9\nlpv_delay_s = 1e9\n").empty());
  EXPECT_THAT(Issues("actuator_position = \"level_up\"\n"),
              ::testing::Contains(HasSubstr("reach[0].actuator_position: channel \"level_up\" has "
                                            "role \"level\"")));
  EXPECT_THAT(Issues("lpv_scheduling = \"nope\"\n"),
              ::testing::Contains(HasSubstr("reach[0].lpv_scheduling: unknown channel")));
  EXPECT_TRUE(Issues("online_models = [\"id\", \"arx\", \"frac-foptd\", \"lpv\"]\n"
                     "lpv_scheduling = \"level_up\"\nactuator_position = \"gate_pos\"\n")
                  .empty());
}

// batch_models: which fits run at the end of an experiment (the fits: process_batch_test).
TEST(OnlineModelsConfig, BatchModelsChooseTheEndOfExperimentFits) {
  const core::ReachSampleProcessorOptions defaults = Build("").pipeline;
  EXPECT_TRUE(defaults.batch_id);
  EXPECT_TRUE(defaults.batch_process_models.empty());
  const core::ReachSampleProcessorOptions set =
      Build("batch_models = [\"frac-foptd\", \"soptd\", \"foptd\"]\n").pipeline;
  EXPECT_FALSE(set.batch_id);
  EXPECT_EQ(set.batch_process_models,
            (std::vector<core::ProcessBatchKind>{core::ProcessBatchKind::kFractionalFoptd,
                                                 core::ProcessBatchKind::kSoptd,
                                                 core::ProcessBatchKind::kFoptd}));
  EXPECT_THAT(
      Issues("batch_models = []\n"),
      ::testing::Contains(HasSubstr("reach[0].batch_models: is empty (allowed: at least "
                                    "one of id, idz, foptd, frac-foptd, soptd, arx, frac-ss)")));
  EXPECT_THAT(Issues("batch_models = [\"id\", \"id\"]\n"),
              ::testing::Contains(HasSubstr("reach[0].batch_models[1]: duplicate model \"id\"")));
  EXPECT_THAT(Issues("batch_models = [\"lpv\"]\n"),
              ::testing::Contains(HasSubstr("\"lpv\" is not allowed (allowed: id, idz, foptd, "
                                            "frac-foptd, soptd, arx, frac-ss)")));
  // arx: the reach's arx orders.
  const core::ReachSampleProcessorOptions arx =
      Build("batch_models = [\"arx\"]\narx_na = 1\narx_nb = 3\n").pipeline;
  EXPECT_EQ(arx.batch_process_models,
            std::vector<core::ProcessBatchKind>{core::ProcessBatchKind::kArx});
  EXPECT_EQ(arx.batch_process.arx_na, 1);
  EXPECT_EQ(arx.batch_process.arx_nb, 3);
}

// idz at the end of experiments, with the p22 prior of the geometry (the fit: idz_fit_plant_test).
TEST(OnlineModelsConfig, IdzBatchModelTakesItsP22Prior) {
  const core::ReachSampleProcessorOptions none = Build("batch_models = [\"idz\"]\n").pipeline;
  ASSERT_TRUE(none.batch_idz.has_value());
  EXPECT_FALSE(none.batch_id);
  EXPECT_LT(none.batch_idz->fit.p22_prior_s_per_m2, 0.0);  // no prior: from the data, or 0
  // The delay range is the ID bank's.
  EXPECT_EQ(none.batch_idz->fit.min_nk, none.online_id.min_delay_samples);
  EXPECT_EQ(none.batch_idz->fit.max_nk, none.online_id.max_delay_samples);
  const core::ReachSampleProcessorOptions prior =
      Build("batch_models = [\"id\", \"idz\"]\nidz_p22_s_per_m2 = 0.0125\n").pipeline;
  ASSERT_TRUE(prior.batch_idz.has_value());
  EXPECT_TRUE(prior.batch_id);
  EXPECT_DOUBLE_EQ(prior.batch_idz->fit.p22_prior_s_per_m2, 0.0125);
  EXPECT_DOUBLE_EQ(prior.batch_idz->fit.p22_prior_std_s_per_m2, 0.2 * 0.0125);
  const core::ReachSampleProcessorOptions with_std =
      Build("batch_models = [\"idz\"]\nidz_p22_s_per_m2 = 0.0125\nidz_p22_std_s_per_m2 = 0.001\n")
          .pipeline;
  EXPECT_DOUBLE_EQ(with_std.batch_idz->fit.p22_prior_std_s_per_m2, 0.001);
  EXPECT_FALSE(Build("").pipeline.batch_idz.has_value());
  // Online: the id bank with the wave front and the prior held.
  const core::ReachSampleProcessorOptions online =
      Build("online_models = [\"id\", \"idz\"]\nidz_p22_s_per_m2 = 0.0125\n").pipeline;
  ASSERT_EQ(online.process_models.size(), 1U);
  EXPECT_EQ(online.process_models[0].kind, core::OnlineModelKind::kIdz);
  EXPECT_DOUBLE_EQ(online.process_models[0].id.outflow_direct_gain_s_per_m2, 0.0125);
  EXPECT_TRUE(online.process_models[0].id.wave_front_term);
  EXPECT_DOUBLE_EQ(online.online_id.outflow_direct_gain_s_per_m2, 0.0);  // id unchanged
  EXPECT_THAT(Issues("idz_p22_s_per_m2 = 0.0125\n"),
              ::testing::Contains(
                  HasSubstr("reach[0].idz_p22_s_per_m2: has no effect: neither batch_models nor "
                            "online_models has \"idz\"")));
  EXPECT_THAT(Issues("batch_models = [\"idz\"]\nidz_p22_std_s_per_m2 = 0.001\n"),
              ::testing::Contains(HasSubstr(
                  "reach[0].idz_p22_std_s_per_m2: has no effect without idz_p22_s_per_m2")));
  EXPECT_THAT(Issues("online_models = [\"idz\"]\nidz_p22_s_per_m2 = 0.0125\n"
                     "idz_p22_std_s_per_m2 = 0.001\n"),
              ::testing::Contains(HasSubstr(
                  "reach[0].idz_p22_std_s_per_m2: has no effect: batch_models has no \"idz\"")));
  EXPECT_THAT(Issues("batch_models = [\"idz\"]\nidz_p22_s_per_m2 = -1.0\n"),
              ::testing::Contains(HasSubstr("reach[0].idz_p22_s_per_m2: -1 is out of range")));
  const config::DaemonConfig c =
      ParseDaemonConfig(Config("batch_models = [\"id\", \"idz\"]\nidz_p22_s_per_m2 = 0.0125\n"
                               "idz_p22_std_s_per_m2 = 0.001\n"),
                        "t.toml");
  EXPECT_EQ(ParseDaemonConfig(RenderDaemonConfig(c), "rendered.toml"), c);
}

// mode = "step": amplitude and hold_s, the PRBS keys refused by name.
TEST(OnlineModelsConfig, StepExperimentKeys) {
  const std::string step =
      "\n[[experiment]]\nname = \"step\"\nreach = \"pool2\"\nmode = \"step\"\n"
      "amplitude = 0.1\nhold_s = 1800.0\n";
  const config::DaemonConfig c = ParseDaemonConfig(Config(step), "t.toml");
  ASSERT_EQ(c.experiments.size(), 1U);
  EXPECT_EQ(c.experiments[0].mode, config::ExperimentMode::kStep);
  EXPECT_EQ(c.experiments[0].hold_s, 1800.0);
  EXPECT_EQ(config::BuildExperimentPlan(c, c.experiments[0], 1.0).step_hold_samples, 30);
  EXPECT_EQ(ParseDaemonConfig(RenderDaemonConfig(c), "rendered.toml"), c);
  EXPECT_THAT(Issues(step + "seed = 3\n"),
              ::testing::Contains(HasSubstr("experiment[0].seed: only allowed when mode = "
                                            "\"design\" or \"explicit\"")));
  EXPECT_THAT(Issues(step + "clock_period_s = 60.0\n"),
              ::testing::Contains(HasSubstr("experiment[0].clock_period_s: only allowed when "
                                            "mode = \"explicit\"")));
  EXPECT_THAT(Issues("\n[[experiment]]\nname = \"s\"\nreach = \"pool2\"\nmode = \"step\"\n"
                     "amplitude = 0.1\n"),
              ::testing::Contains(HasSubstr("experiment[0].hold_s: missing (required)")));
}

// The effective configuration canalidd publishes reads back to the same configuration.
TEST(OnlineModelsConfig, RenderedConfigurationReadsBackTheSame) {
  const config::DaemonConfig c = ParseDaemonConfig(
      Config("online_models = [\"id\", \"lpv\"]\nlpv_scheduling = \"level_up\"\n"
             "batch_models = [\"id\", \"frac-foptd\"]\n"
             "actuator_position = \"gate_pos\"\nfractional_alphas = [0.7, 0.95]\narx_na = 3\n"),
      "t.toml");
  EXPECT_EQ(ParseDaemonConfig(RenderDaemonConfig(c), "rendered.toml"), c);
}

}  // namespace
}  // namespace canalid::daemon

// The results register map's layout and image: every address fits, every parameter an online
// estimator publishes has its place, and a reader decodes what was set (f32 words decoded with
// register_codec's independent of the writer's path: libmodbus's own float helper in the server
// suite).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/online/online_model.h"
#include "core/registers/register_codec.h"
#include "core/results/results_image.h"
#include "core/results/results_layout.h"

namespace canalid::core {
namespace {

float F32(const std::vector<std::uint16_t>& w, int at) {
  return DecodeFloat32(std::span<const std::uint16_t, 2>(w.data() + at, 2),
                       WordOrder::kHighWordFirst);
}
std::uint32_t U32(const std::vector<std::uint16_t>& w, int at) {
  return DecodeUint32(std::span<const std::uint16_t, 2>(w.data() + at, 2),
                      WordOrder::kHighWordFirst);
}
std::vector<std::uint16_t> ReadAll(const ResultsImage& image, double now_s) {
  std::vector<std::uint16_t> words(static_cast<std::size_t>(image.size()));
  image.Read(now_s, 0, words);
  return words;
}
int ParamAddress(int reach, const std::string& kind, bool batch, const std::string& param) {
  const ResultsKind* k = FindResultsKind(kind);
  for (std::size_t i = 0; i < k->params.size(); ++i) {
    if (k->params[i] == param) {
      return ResultsSlotAddress(reach, *k, batch) + kResultsSlotHeaderWords +
             kResultsWordsPerParam * static_cast<int>(i);
    }
  }
  ADD_FAILURE() << kind << " has no parameter " << param;
  return 0;
}

TEST(ResultsLayout, EverySlotFitsItsSectionAndEveryAddressSixteenBits) {
  int end = 0;
  for (const ResultsKind& kind : ResultsKinds()) {
    EXPECT_EQ(kind.offset, end) << kind.name;
    end += kind.words();
    const std::set<std::string> unique(kind.params.begin(), kind.params.end());
    EXPECT_EQ(unique.size(), kind.params.size()) << kind.name << ": a parameter twice";
  }
  EXPECT_GE(kResultsOnlineOffset, kReachStatusWords);
  EXPECT_LE(kResultsOnlineOffset + end, kResultsBatchOffset);
  EXPECT_LE(kResultsBatchOffset + end, kResultsReachStride);
  EXPECT_LE(ResultsImageWords(kResultsMaxReaches), 65536);
  EXPECT_THROW(ResultsImage(std::vector<std::string>(kResultsMaxReaches + 1, "r"), 0.0),
               std::invalid_argument);
}

// Each online kind at its largest orders: every parameter its snapshot names has a place.
TEST(ResultsLayout, EveryOnlineParameterHasAPlace) {
  OnlineModelSettings s;
  s.sample_time_s = 10.0;
  s.max_delay_s = 100.0;
  s.wave_front_term = true;
  s.frac_ss_q = 4;
  std::vector<std::pair<int, int>> arx_orders{{15, 1}, {0, 16}, {8, 8}};
  for (const OnlineModelKind kind : kOnlineModelKinds) {
    for (const auto& [na, nb] : arx_orders) {
      s.arx_na = s.lpv_na = na;
      s.arx_nb = s.lpv_nb = nb;
      const auto model = MakeOnlineModel(OnlineModelOptionsFor(kind, s));
      OnlineModelSnapshot snapshot;
      model->FillSnapshot(snapshot);
      const ResultsKind* slot = FindResultsKind(OnlineModelKindName(kind));
      ASSERT_NE(slot, nullptr) << OnlineModelKindName(kind);
      for (int i = 0; i < snapshot.num_params; ++i) {
        const std::string& name = snapshot.names[static_cast<std::size_t>(i)];
        EXPECT_NE(std::find(slot->params.begin(), slot->params.end(), name), slot->params.end())
            << OnlineModelKindName(kind) << " na " << na << " nb " << nb << ": " << name;
      }
    }
  }
}

TEST(ResultsImage, HeaderAndReachNamesAreInPlace) {
  const ResultsImage image({"pool2", "a_reach_name_longer_than_16"}, 1000.0);
  const auto w = ReadAll(image, 1234.9);
  EXPECT_EQ(w[kHeaderVersion], kResultsMapVersion);
  EXPECT_EQ(w[kHeaderReachCount], 2);
  EXPECT_EQ(w[kHeaderFirstReach], kResultsFirstReach);
  EXPECT_EQ(w[kHeaderReachStride], kResultsReachStride);
  EXPECT_EQ(U32(w, kHeaderUptime), 234u);
  const int base = ResultsReachAddress(0);
  EXPECT_EQ(w[static_cast<std::size_t>(base)], ('p' << 8) | 'o');
  EXPECT_EQ(w[static_cast<std::size_t>(base) + 2], '2' << 8);
  EXPECT_EQ(w[static_cast<std::size_t>(base) + 3], 0);
  // 16 bytes, no terminator: "a_reach_name_lon".
  const int second = ResultsReachAddress(1);
  EXPECT_EQ(w[static_cast<std::size_t>(second) + 7], ('o' << 8) | 'n');
  EXPECT_EQ(w[static_cast<std::size_t>(second + kReachCommsStatus)], kResultsNoPollYet);
  EXPECT_TRUE(std::isnan(F32(w, second + kReachPollAge)));
  EXPECT_TRUE(std::isnan(F32(w, ParamAddress(1, "id", false, "area_m2"))));
  EXPECT_EQ(image.FindReach("a_reach_name_longer_than_16"), 1);
  EXPECT_EQ(image.FindReach("other"), -1);
}

TEST(ResultsImage, AModelGoesToItsSlotByNameWithItsAge) {
  ResultsImage image({"p1", "p2"}, 0.0);
  const std::vector<std::string> names{"delay_s", "area_m2", "not_a_param", "p21_s_per_m2"};
  const std::vector<double> values{540.0, 31234.56789, 7.0, 0.0123};
  const std::vector<double> std_devs{0.0, 812.5, 1.0, std::numeric_limits<double>::quiet_NaN()};
  ResultsModel m{"id", "rls-bank", 5000.0, 1234567, names, values, std_devs, 4 | 16, 0.0042};
  ASSERT_TRUE(image.SetModel(1, m));
  const auto w = ReadAll(image, 5012.5);
  const int slot = ResultsSlotAddress(1, *FindResultsKind("id"), false);
  EXPECT_EQ(w[static_cast<std::size_t>(slot + kSlotPublished)], 1);
  EXPECT_EQ(w[static_cast<std::size_t>(slot + kSlotEstimator)], 1);
  EXPECT_EQ(w[static_cast<std::size_t>(slot + kSlotFlags)], 20);
  EXPECT_EQ(w[static_cast<std::size_t>(slot + kSlotUnmapped)], 1);
  EXPECT_FLOAT_EQ(F32(w, slot + kSlotAge), 12.5f);
  EXPECT_EQ(U32(w, slot + kSlotSamples), 1234567u);
  EXPECT_EQ(F32(w, slot + kSlotErrorRms), 0.0042f);
  EXPECT_EQ(F32(w, ParamAddress(1, "id", false, "delay_s")), 540.0f);
  EXPECT_EQ(F32(w, ParamAddress(1, "id", false, "area_m2")), static_cast<float>(31234.56789));
  EXPECT_EQ(F32(w, ParamAddress(1, "id", false, "area_m2") + 2), 812.5f);
  EXPECT_EQ(F32(w, ParamAddress(1, "id", false, "p21_s_per_m2")), 0.0123f);
  EXPECT_TRUE(std::isnan(F32(w, ParamAddress(1, "id", false, "p21_s_per_m2") + 2)));
  EXPECT_TRUE(std::isnan(F32(w, ParamAddress(1, "id", false, "b"))));
  // The reach's health word ORs its online models' flags; reach 0 and the batch slot are untouched.
  EXPECT_EQ(w[static_cast<std::size_t>(ResultsReachAddress(1) + kReachHealth)], 20);
  EXPECT_EQ(w[static_cast<std::size_t>(ResultsReachAddress(0) + kReachHealth)], 0);
  EXPECT_EQ(w[static_cast<std::size_t>(ResultsSlotAddress(1, *FindResultsKind("id"), true))], 0);
  EXPECT_TRUE(std::isnan(F32(w, ParamAddress(1, "id", true, "delay_s"))));
  EXPECT_EQ(w[kHeaderChanges], 1);

  // A later model with fewer parameters leaves none of the earlier ones behind.
  const std::vector<std::string> fewer{"area_m2"};
  const std::vector<double> one{30000.0}, none{std::nan("")};
  image.SetModel(1, {"id", "rls-bank", 5001.0, 2, fewer, one, none, 0, 0.0});
  const auto w2 = ReadAll(image, 5001.0);
  EXPECT_TRUE(std::isnan(F32(w2, ParamAddress(1, "id", false, "delay_s"))));
  EXPECT_EQ(F32(w2, ParamAddress(1, "id", false, "area_m2")), 30000.0f);
  EXPECT_EQ(w2[static_cast<std::size_t>(slot + kSlotUnmapped)], 0);
  EXPECT_EQ(w2[static_cast<std::size_t>(ResultsReachAddress(1) + kReachHealth)], 0);
}

TEST(ResultsImage, BatchAndPersistedModelsFillTheBatchSlot) {
  ResultsImage image({"p1"}, 0.0);
  const std::vector<std::string> names{"gain", "time_constant_s", "alpha"};
  const std::vector<double> values{0.5, 1200.0, 0.7};
  const std::vector<double> std_devs(3, std::nan(""));
  EXPECT_TRUE(
      image.SetModel(0, {"frac-foptd", "persisted", 10.0, 900, names, values, std_devs, 32, 0.01}));
  EXPECT_FALSE(
      image.SetModel(0, {"no-such-kind", "batch", 10.0, 1, names, values, std_devs, 0, 0}));
  EXPECT_FALSE(image.SetModel(3, {"frac-foptd", "batch", 10.0, 1, names, values, std_devs, 0, 0}));
  const auto w = ReadAll(image, 20.0);
  const int slot = ResultsSlotAddress(0, *FindResultsKind("frac-foptd"), true);
  EXPECT_EQ(w[static_cast<std::size_t>(slot + kSlotEstimator)], 5);
  EXPECT_EQ(F32(w, ParamAddress(0, "frac-foptd", true, "alpha")), 0.7f);
  EXPECT_EQ(F32(w, ParamAddress(0, "frac-foptd", true, "time_constant_s")), 1200.0f);
  // Batch flags (out of bounds) are the slot's, not the reach's online health.
  EXPECT_EQ(w[static_cast<std::size_t>(slot + kSlotFlags)], 32);
  EXPECT_EQ(w[static_cast<std::size_t>(ResultsReachAddress(0) + kReachHealth)], 0);
  EXPECT_EQ(w[kHeaderChanges], 1);
}

TEST(ResultsImage, PollsAndExperimentFillTheReachStatus) {
  ResultsImage image({"p1"}, 0.0);
  const int base = ResultsReachAddress(0);
  image.SetPoll(0, {100.0, 0, 0, 2.125});
  image.SetPoll(0, {101.0, 2, 4, std::nan("")});
  image.SetExperiment(0, {3, 0, 0.25, 3600.0, 1.5});
  const auto w = ReadAll(image, 103.0);
  EXPECT_EQ(w[static_cast<std::size_t>(base + kReachCommsStatus)], 2);
  EXPECT_EQ(w[static_cast<std::size_t>(base + kReachExceptionCode)], 4);
  EXPECT_FLOAT_EQ(F32(w, base + kReachPollAge), 2.0f);
  EXPECT_FLOAT_EQ(F32(w, base + kReachGoodPollAge), 3.0f);
  EXPECT_EQ(U32(w, base + kReachPolls), 2u);
  EXPECT_EQ(U32(w, base + kReachFailedPolls), 1u);
  EXPECT_TRUE(std::isnan(F32(w, base + kReachLevel)));
  EXPECT_EQ(w[static_cast<std::size_t>(base + kReachExperimentState)], 3);
  EXPECT_EQ(F32(w, base + kReachProgress), 0.25f);
  EXPECT_EQ(F32(w, base + kReachTimeLeft), 3600.0f);
  EXPECT_EQ(F32(w, base + kReachSetpoint), 1.5f);
}

// A request may start or end in the middle of a computed field: it gets that field's words.
TEST(ResultsImage, APartialReadOfAnAgeGetsItsHalf) {
  ResultsImage image({"p1"}, 0.0);
  image.SetPoll(0, {100.0, 0, 0, 1.0});
  // 50.1 s: both halves of the f32 are non-zero (the stored words are zero).
  const auto all = ReadAll(image, 150.1);
  const int at = ResultsReachAddress(0) + kReachPollAge;
  ASSERT_NE(all[static_cast<std::size_t>(at)], 0);
  ASSERT_NE(all[static_cast<std::size_t>(at) + 1], 0);
  std::array<std::uint16_t, 1> high{}, low{};
  image.Read(150.1, at, high);
  image.Read(150.1, at + 1, low);
  EXPECT_EQ(high[0], all[static_cast<std::size_t>(at)]);
  EXPECT_EQ(low[0], all[static_cast<std::size_t>(at) + 1]);
  EXPECT_FLOAT_EQ(F32(all, at), 50.1f);
  std::array<std::uint16_t, 1> uptime_low{};
  image.Read(150.0, kHeaderUptime + 1, uptime_low);
  EXPECT_EQ(uptime_low[0], 150);
}

// docs/results-register-map.md shows the map the table gives (for the demo's one reach, pool2):
// the doc cannot drift from the code.  On a change, paste the text this test prints.
TEST(ResultsLayout, TheDocShowsTheMapTheTableGives) {
  std::ifstream in(std::string(CANALID_SOURCE_DIR) + "/docs/results-register-map.md");
  std::stringstream doc;
  doc << in.rdbuf();
  const std::vector<std::string> reaches{"pool2"};
  const std::string tables = ResultsMapMarkdown(reaches);
  EXPECT_NE(doc.str().find(tables), std::string::npos)
      << "docs/results-register-map.md lacks the generated tables:\n"
      << tables;
}

}  // namespace
}  // namespace canalid::core

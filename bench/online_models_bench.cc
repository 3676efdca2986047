// The per-sample cost of each kind of the online model registry as the daemon runs it (Update and
// FillSnapshot for the publication), against its bank driven directly (the peer: the registry's
// adapter cost is the difference), and of one reach running every kind.  Settings: the daemon's
// defaults for pool 2 of ASCE canal 2 (Ts 60 s, delays 0..1400 s: 24 candidates; 8 alphas; LPV
// ARX(1, 1)).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "core/online/online_model.h"
#include "core/reach/reach_sample_processor.h"

namespace canalid::core {
namespace {

constexpr std::size_t kRecord = 4096;  // a power of two: the index wraps with a mask

struct Record {
  std::vector<OnlineSample> samples;
};

// A pool under a two-level inflow: level integrates the net flow; the gate follows the inflow.
Record PoolRecord() {
  Record r;
  std::uint64_t state = 11;
  double level = 2.0;
  for (std::size_t k = 0; k < kRecord; ++k) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const double sign = (state >> 63) != 0U ? 1.0 : -1.0;
    OnlineSample s;
    s.q_in_m3s = 10.0 + 0.7 * sign;
    s.q_out_m3s = 10.0;
    level += 60.0 / 34000.0 * (s.q_in_m3s - s.q_out_m3s) * 0.1;
    s.level_m = level;
    s.input = 1.5 + 0.1 * sign;
    s.scheduling = level;
    r.samples.push_back(s);
  }
  return r;
}

OnlineModelSettings PoolSettings() {
  OnlineModelSettings s;
  s.sample_time_s = 60.0;
  s.max_delay_s = 1400.0;
  s.fractional_delay_s = 660.0;
  s.lpv_delay_s = 660.0;
  s.frac_ss_delay_s = 660.0;
  return s;
}

// Arg: the kind (OnlineModelKind).
void BM_OnlineModelSample(benchmark::State& state) {
  const auto kind = static_cast<OnlineModelKind>(state.range(0));
  auto model = MakeOnlineModel(OnlineModelOptionsFor(kind, PoolSettings()));
  const Record record = PoolRecord();
  OnlineModelSnapshot snapshot;
  std::size_t k = 0;
  for (auto _ : state) {
    model->Update(record.samples[k]);
    model->FillSnapshot(snapshot);
    benchmark::DoNotOptimize(snapshot.values[0]);
    k = (k + 1) & (kRecord - 1);
  }
  state.SetLabel(std::string(OnlineModelKindName(kind)) + " (registry, update + snapshot)");
}
BENCHMARK(BM_OnlineModelSample)->DenseRange(0, static_cast<int>(kOnlineModelKinds.size()) - 1);

// The peers: the same banks without the registry (same options, deviations done by hand).
// `step(sample)` updates the bank and returns a snapshot value.
template <class Step>
void RunDirect(benchmark::State& state, const char* label, Step step) {
  const Record record = PoolRecord();
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(step(record.samples[k]));
    k = (k + 1) & (kRecord - 1);
  }
  state.SetLabel(label);
}

void BM_DirectIdBank(benchmark::State& state) {
  OnlineIntegratorDelayBank bank(
      OnlineModelOptionsFor(OnlineModelKind::kIntegratorDelay, PoolSettings()).id);
  RunDirect(state, "id (bank direct)", [&](const OnlineSample& s) {
    bank.Update(s.q_in_m3s, s.q_out_m3s, s.level_m);
    return bank.Snapshot().b;
  });
}
BENCHMARK(BM_DirectIdBank);

// The ID bank's update alone (no snapshot), as the replay of config/canalidd-asce2.toml runs it
// on every poll: the bank's part of a replay's cost per sample.
void BM_IdBankUpdate(benchmark::State& state) {
  OnlineIntegratorDelayBank bank(
      OnlineModelOptionsFor(OnlineModelKind::kIntegratorDelay, PoolSettings()).id);
  RunDirect(state, "id (bank update only)",
            [&](const OnlineSample& s) { return bank.Update(s.q_in_m3s, s.q_out_m3s, s.level_m); });
}
BENCHMARK(BM_IdBankUpdate);

void BM_DirectArxBank(benchmark::State& state) {
  OnlineArxBank bank(OnlineModelOptionsFor(OnlineModelKind::kArx, PoolSettings()).arx);
  RunDirect(state, "arx (bank direct)", [&](const OnlineSample& s) {
    bank.Update(s.input - 1.5, s.level_m - 2.0);
    return bank.Snapshot().a(0);
  });
}
BENCHMARK(BM_DirectArxBank);

void BM_DirectFractionalBank(benchmark::State& state) {
  OnlineFractionalBank bank(
      OnlineModelOptionsFor(OnlineModelKind::kFractionalFoptd, PoolSettings()).fractional);
  RunDirect(state, "frac-foptd (bank direct)", [&](const OnlineSample& s) {
    bank.Update(s.input - 1.5, s.level_m - 2.0);
    return bank.Snapshot().gain;
  });
}
BENCHMARK(BM_DirectFractionalBank);

void BM_DirectCommensurate(benchmark::State& state) {
  OnlineCommensurate estimator(
      OnlineModelOptionsFor(OnlineModelKind::kFracSs, PoolSettings()).frac_ss);
  RunDirect(state, "frac-ss (estimator direct)", [&](const OnlineSample& s) {
    estimator.Update(s.input - 1.5, s.level_m - 2.0);
    return estimator.a(1);
  });
}
BENCHMARK(BM_DirectCommensurate);

// One reach running id, arx, frac-foptd, lpv and frac-ss: the daemon's per-poll estimator cost.
void BM_ReachEveryKind(benchmark::State& state) {
  const OnlineModelSettings settings = PoolSettings();
  ReachSampleProcessorOptions options;
  options.sample_time_s = settings.sample_time_s;
  options.online_id = OnlineModelOptionsFor(OnlineModelKind::kIntegratorDelay, settings).id;
  for (const OnlineModelKind kind : {OnlineModelKind::kArx, OnlineModelKind::kFractionalFoptd,
                                     OnlineModelKind::kLpvArx, OnlineModelKind::kFracSs}) {
    options.process_models.push_back(OnlineModelOptionsFor(kind, settings));
  }
  ReachSampleProcessor reach(options);
  const Record record = PoolRecord();
  OnlineModelSnapshot snapshot;
  std::size_t k = 0;
  for (auto _ : state) {
    const OnlineSample& o = record.samples[k];
    ReachSample s;
    s.q_in_m3s = o.q_in_m3s;
    s.q_out_m3s = o.q_out_m3s;
    s.level_m = o.level_m;
    s.q_in_valid = s.q_out_valid = s.level_valid = true;
    s.input = o.input;
    s.scheduling = o.scheduling;
    const ReachActions actions = reach.OnSample(s);
    for (std::size_t i = 0; i < reach.online_models().size(); ++i) {
      if ((actions.online_models_updated >> i) & 1U) {
        reach.online_models()[i]->FillSnapshot(snapshot);
      }
    }
    benchmark::DoNotOptimize(snapshot.values[0]);
    k = (k + 1) & (kRecord - 1);
  }
  state.SetLabel("reach: id + arx + frac-foptd + lpv + frac-ss");
}
BENCHMARK(BM_ReachEveryKind);

}  // namespace
}  // namespace canalid::core

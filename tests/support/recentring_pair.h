#pragma once
#include <cstddef>

#include "core/online/online_integrator_delay.h"

namespace canalid::testing {

/// The snapshots of candidate `delay_samples` of two banks run over the same record: one that
/// re-centres every 50 samples (`recentred`) and one that never does (`plain`).
struct RecentringPair {
  core::IntegratorDelaySnapshot recentred;
  core::IntegratorDelaySnapshot plain;
};

/// `record` has q_in, q_out and level (equal lengths); `options` is taken as it is but for
/// recentre_samples.
template <class Record>
RecentringPair RunWithAndWithoutRecentring(core::OnlineIntegratorDelayOptions options,
                                           const Record& record, int delay_samples) {
  options.recentre_samples = 50;
  core::OnlineIntegratorDelayBank recentred(options);
  options.recentre_samples = -1;
  core::OnlineIntegratorDelayBank plain(options);
  for (std::size_t k = 0; k < record.level.size(); ++k) {
    recentred.Update(record.q_in[k], record.q_out[k], record.level[k]);
    plain.Update(record.q_in[k], record.q_out[k], record.level[k]);
  }
  return {recentred.CandidateSnapshot(delay_samples), plain.CandidateSnapshot(delay_samples)};
}

}  // namespace canalid::testing

#include "daemon/canalid/online_settings_flags.h"

#include <cstdio>
#include <string>

#include "daemon/canalid/input_error.h"
#include "daemon/config/daemon_config.h"

namespace canalid::cli {

core::OnlineModelSettings OnlineSettingsFromFlags(const IdentifyOptions& options,
                                                  const drivers::CsvTable& table) {
  const auto method = config::EnumFromName<core::RlsMethod>(options.method);
  if (!method) {
    throw InputError("--method " + options.method +
                     ": unknown (allowed: " + config::AllowedNames<core::RlsMethod>() + ")");
  }
  if (!(options.forgetting > 0.0 && options.forgetting <= 1.0)) {
    char value[32];
    std::snprintf(value, sizeof value, "%g", options.forgetting);
    throw InputError(std::string("--forgetting ") + value + ": out of range (0 < L <= 1)");
  }
  if (options.initial_covariance &&
      !(*options.initial_covariance > 0.0 && *options.initial_covariance <= 1e20)) {
    char value[32];
    std::snprintf(value, sizeof value, "%g", *options.initial_covariance);
    throw InputError(std::string("--initial-covariance ") + value +
                     ": out of range (0 < p0 <= 1e20)");
  }
  core::OnlineModelSettings s;
  s.sample_time_s = table.sample_time_s();
  s.rls_method = *method;
  s.forgetting = options.forgetting;
  s.initial_covariance = options.initial_covariance;
  return s;
}

}  // namespace canalid::cli

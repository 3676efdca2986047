#include "daemon/canalid/rls_health_json.h"

namespace canalid::cli {

nlohmann::json RlsHealthJson(const core::RlsHealth& h) {
  return {{"trace_p", h.trace_p},
          {"condition", h.condition_estimate},
          {"excitation", h.excitation},
          {"innovation_variance", h.innovation_variance},
          {"frozen", h.frozen},
          {"wound_up", h.wound_up},
          {"updates", h.updates},
          {"rejected_invalid", h.rejected_invalid},
          {"rejected_outliers", h.rejected_outliers},
          {"clipped", h.clipped},
          {"dead_zone", h.dead_zone},
          {"frozen_count", h.frozen_count},
          {"projections", h.projections},
          {"resets", h.resets},
          {"trace_bounded", h.trace_bounded}};
}

}  // namespace canalid::cli

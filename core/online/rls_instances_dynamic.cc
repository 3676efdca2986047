// Rls<Eigen::Dynamic>, compiled once here (rls.h declares it extern; the sizes are split over three
// files so that they compile in parallel).
#include "core/online/rls.h"

namespace canalid::core {

CANALID_RLS_SIZE(, Eigen::Dynamic)

}  // namespace canalid::core

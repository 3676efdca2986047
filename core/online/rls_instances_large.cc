// Rls of 5 to 8 parameters, compiled once here (rls.h declares them extern; the sizes are split
// over three files so that they compile in parallel).
#include "core/online/rls.h"

namespace canalid::core {

CANALID_RLS_LARGE_SIZES()

}  // namespace canalid::core

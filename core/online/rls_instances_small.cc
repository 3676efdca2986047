// Rls of 1 to 4 parameters, compiled once here (rls.h declares them extern; the sizes are split
// over three files so that they compile in parallel).
#include "core/online/rls.h"

namespace canalid::core {

CANALID_RLS_SMALL_SIZES()

}  // namespace canalid::core

// RlsBank of the sizes canalid uses, compiled once here (rls_bank.h declares them extern).
#include "core/online/rls_bank.h"

namespace canalid::core {

CANALID_RLS_BANK_SIZES()

}  // namespace canalid::core

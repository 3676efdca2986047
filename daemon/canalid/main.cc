#include "core/system/guarded_main.h"
#include "daemon/canalid/cli.h"

int main(int argc, char** argv) {
  return canalid::core::GuardedMain("canalid", canalid::cli::Run, argc, argv);
}

#include "tests/support/build_paths.h"

namespace canalid::test {

const char* SourceDirectory() { return CANALID_PATH_SOURCE; }
const char* ReferenceDirectory() { return CANALID_PATH_REFERENCE; }
const char* BinaryDirectory() { return CANALID_PATH_BINARY; }

}  // namespace canalid::test

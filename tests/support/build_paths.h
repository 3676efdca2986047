#pragma once
// The checkout and the build tree the tests read files from and run programs of. The build
// includes this header in every test file (-include, tests/support/CMakeLists.txt) and compiles
// the paths into build_paths.cc alone: written into every test file's compile command, they made
// each test file a compiler-cache miss in a checkout at another path (a CI clone), about 700 s of
// compiling.
namespace canalid::test {

const char* SourceDirectory();     ///< the checkout (PROJECT_SOURCE_DIR)
const char* ReferenceDirectory();  ///< its tests/data/reference
const char* BinaryDirectory();     ///< the build tree (PROJECT_BINARY_DIR)

}  // namespace canalid::test

#define CANALID_SOURCE_DIR (::canalid::test::SourceDirectory())
#define CANALID_REFERENCE_DIR (::canalid::test::ReferenceDirectory())
#define CANALID_BINARY_DIR (::canalid::test::BinaryDirectory())

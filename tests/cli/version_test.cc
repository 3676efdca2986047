// Every program prints "<program> <version>" for --version, with the version of project(VERSION)
// in CMakeLists.txt (passed to this suite as CANALID_PROJECT_VERSION), and exits 0 even where the
// program otherwise requires options or a subcommand.
#include <gtest/gtest.h>

#include <string>

#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

struct Program {
  std::string name;
  std::string path;  // relative to the build tree
};

class VersionTest : public ::testing::TestWithParam<Program> {};

TEST_P(VersionTest, PrintsProgramAndProjectVersion) {
  const Program& program = GetParam();
  const auto dir = TestDirectory("version_" + program.name);
  const ProgramRun run =
      RunProgram(std::string(CANALID_BINARY_DIR) + "/" + program.path + " --version", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, program.name + " " + CANALID_PROJECT_VERSION + "\n");
  EXPECT_EQ(run.err, "");
}

INSTANTIATE_TEST_SUITE_P(Programs, VersionTest,
                         ::testing::Values(Program{"canalid", "daemon/canalid/canalid"},
                                           Program{"canalidd", "daemon/canalidd/canalidd"},
                                           Program{"canalid-command",
                                                   "daemon/command/canalid-command"},
                                           Program{"canalsim", "sim/canalsim"}),
                         [](const ::testing::TestParamInfo<Program>& param_info) {
                           std::string name;
                           for (const char c : param_info.param.name) name += c == '-' ? '_' : c;
                           return name;
                         });

}  // namespace
}  // namespace canalid::testing

// `--closed-loop` has one parser (daemon/canalid/closed_loop_option.h) and one meaning: every
// command that takes it accepts and refuses the same values, and "on" is the three-step method in
// the batch fit and online alike.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "daemon/canalid/closed_loop_option.h"
#include "daemon/canalid/input_error.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

using core::ClosedLoopMode;

TEST(ClosedLoopOption, OneMeaningPerValue) {
  EXPECT_EQ(cli::ParseClosedLoop("auto"), ClosedLoopMode::kAuto);
  EXPECT_EQ(cli::ParseClosedLoop("on"), ClosedLoopMode::kThreeStep);
  EXPECT_EQ(cli::ParseClosedLoop("three-step"), ClosedLoopMode::kThreeStep);
  EXPECT_EQ(cli::ParseClosedLoop("iv"), ClosedLoopMode::kOn);
  EXPECT_EQ(cli::ParseClosedLoop("off"), ClosedLoopMode::kOff);
  for (const char* bad : {"", "ON", "yes", "true", "1", "three_step", "auto "}) {
    EXPECT_THROW(cli::ParseClosedLoop(bad), cli::InputError) << '"' << bad << '"';
  }
}

// The commands that take --closed-loop, each with everything else it needs; the input file does
// not exist, so an accepted value gets as far as reading it and a refused one stops at the option.
const std::vector<std::string>& Commands() {
  static const std::vector<std::string> kCommands = {
      "identify --model id --input missing.csv",
      "identify --model id --online --input missing.csv",
      "report --model id --input missing.csv --out report",
  };
  return kCommands;
}

TEST(ClosedLoopOption, EveryCommandAcceptsTheSameValues) {
  const auto dir = TestDirectory("closed_loop_option_accepts");
  for (const std::string& command : Commands()) {
    for (const char* value : cli::kClosedLoopValues) {
      const ProgramRun run =
          RunProgramWithin(CanalidProgram() + " " + command + " --closed-loop " + value, dir, 60);
      EXPECT_EQ(run.exit_code, 2) << command << " " << value << ": " << run.err;
      EXPECT_EQ(run.err.find("--closed-loop"), std::string::npos)
          << command << " --closed-loop " << value << ": " << run.err;
      EXPECT_NE(run.err.find("missing.csv"), std::string::npos) << run.err;
    }
  }
}

TEST(ClosedLoopOption, EveryCommandRefusesTheSameValues) {
  const auto dir = TestDirectory("closed_loop_option_refuses");
  for (const std::string& command : Commands()) {
    for (const char* value : {"ON", "yes", "three_step", "1"}) {
      const ProgramRun run =
          RunProgramWithin(CanalidProgram() + " " + command + " --closed-loop " + value, dir, 60);
      EXPECT_EQ(run.exit_code, 2) << command << " " << value << ": " << run.err;
      EXPECT_NE(run.err.find("--closed-loop"), std::string::npos) << command << ": " << run.err;
      EXPECT_NE(run.err.find("is not one of auto, on, three-step, iv, off"), std::string::npos)
          << command << ": " << run.err;
    }
  }
}

// The help of every command that takes the option documents the same values.
TEST(ClosedLoopOption, HelpOfEveryCommandListsTheValues) {
  const auto dir = TestDirectory("closed_loop_option_help");
  for (const std::string command : {"identify", "report"}) {
    const ProgramRun run = RunProgramWithin(CanalidProgram() + " " + command + " --help", dir, 60);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("--closed-loop"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("auto|on|three-step|iv|off"), std::string::npos) << run.out;
  }
}

// "iv" is the online bank's: the batch fit refuses it instead of running something else.
TEST(ClosedLoopOption, BatchFitRefusesIv) {
  const auto dir = TestDirectory("closed_loop_option_batch_iv");
  WriteFile(dir / "r.csv", "time_s,q_in,q_out,level\n0,1,1,1\n1,1,1,1\n2,1,1,1\n3,1,1,1\n");
  const ProgramRun run =
      RunProgramWithin(CanalidProgram() + " identify --model id --closed-loop iv --input " +
                           (dir / "r.csv").string(),
                       dir, 60);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("--closed-loop iv"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace canalid::testing

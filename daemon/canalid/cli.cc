#include "daemon/canalid/cli.h"

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

namespace canalid::cli {

int Run(int argc, char** argv) {
  CLI::App app{"canalid: identification of canal pools from experiment data"};
  app.require_subcommand(1);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "canalid: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace canalid::cli

#include "daemon/canalid/cli.h"

int main(int argc, char** argv) { return canalid::cli::Run(argc, argv); }

// Replays fuzz inputs without libFuzzer: runs the target's LLVMFuzzerTestOneInput over every
// regular file of the directories (or files) given, in name order, so the committed corpus of
// each target (tests/fuzz/corpus/<name>/) is a regression test in the normal GCC build (ctest -L
// fuzz).  Fails, naming the input, on an exception that escapes the target; a crash or abort
// (a property check of the target) prints the input's path before the process dies.  An empty
// or missing corpus is a failure too: a test that replays nothing proves nothing.
#include <unistd.h>
#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

// The input being replayed, for the signal handler (which may only write(2) it).
char current_input[4096] = "";

void OnFatalSignal(int signal) {
  static const char kPrefix[] = "replay: fatal signal while running ";
  [[maybe_unused]] ssize_t n = write(STDERR_FILENO, kPrefix, sizeof(kPrefix) - 1);
  n = write(STDERR_FILENO, current_input, std::strlen(current_input));
  n = write(STDERR_FILENO, "\n", 1);
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

std::vector<std::filesystem::path> Inputs(const std::filesystem::path& path) {
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_directory(path)) {
    for (const auto& entry : std::filesystem::directory_iterator(path))
      if (entry.is_regular_file()) files.push_back(entry.path());
  } else if (std::filesystem::is_regular_file(path)) {
    files.push_back(path);
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR_OR_FILE...\n", argv[0]);
    return 2;
  }
  for (int s : {SIGSEGV, SIGABRT, SIGFPE, SIGBUS, SIGILL}) std::signal(s, OnFatalSignal);
  int replayed = 0;
  int failures = 0;
  for (int a = 1; a < argc; ++a) {
    const std::vector<std::filesystem::path> files = Inputs(argv[a]);
    if (files.empty()) {
      std::fprintf(stderr, "replay: %s: no inputs (missing or empty corpus)\n", argv[a]);
      return 1;
    }
    for (const std::filesystem::path& file : files) {
      std::snprintf(current_input, sizeof(current_input), "%s", file.c_str());
      std::ifstream in(file, std::ios::binary);
      const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
      if (!in.good() && !in.eof()) {
        std::fprintf(stderr, "replay: %s: cannot read\n", file.c_str());
        return 1;
      }
      try {
        LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
      } catch (const std::exception& e) {
        std::fprintf(stderr, "replay: %s: uncaught exception: %s\n", file.c_str(), e.what());
        ++failures;
      } catch (...) {
        std::fprintf(stderr, "replay: %s: uncaught exception of unknown type\n", file.c_str());
        ++failures;
      }
      ++replayed;
    }
  }
  std::printf("replay: %d inputs, %d failures\n", replayed, failures);
  return failures == 0 ? 0 : 1;
}

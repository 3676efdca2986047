#include "daemon/canalid/child_process.h"

#include "core/system/errno_text.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

extern char** environ;

namespace canalid::cli {
namespace {

// posix_spawn file actions, released on every path out.
class FileActions {
 public:
  FileActions() { posix_spawn_file_actions_init(&actions_); }
  ~FileActions() { posix_spawn_file_actions_destroy(&actions_); }
  FileActions(const FileActions&) = delete;
  FileActions& operator=(const FileActions&) = delete;
  posix_spawn_file_actions_t* get() { return &actions_; }

 private:
  posix_spawn_file_actions_t actions_;
};

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

ChildResult RunChild(const std::string& program, const std::vector<std::string>& args,
                     const std::filesystem::path& working_dir,
                     const std::filesystem::path& stderr_path) {
  // The stderr file is opened by the parent so that its path is independent of working_dir.
  const std::filesystem::path error_file = std::filesystem::absolute(stderr_path);
  FileActions actions;
  posix_spawn_file_actions_addopen(actions.get(), 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(actions.get(), 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(actions.get(), 2, error_file.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addchdir_np(actions.get(), working_dir.c_str());
  // A relative path names a file from where canalid runs, not from working_dir.
  const std::string file = program.find('/') == std::string::npos
                               ? program
                               : std::filesystem::absolute(program).string();
  std::vector<std::string> storage;
  storage.push_back(file);
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(storage.size() + 1);
  for (auto& s : storage) argv.push_back(s.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, file.c_str(), actions.get(), nullptr, argv.data(), environ);
  if (rc != 0) {
    throw ToolError("cannot run '" + program + "': " + core::ErrnoText(rc));
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw ToolError("waiting for '" + program + "': " + core::ErrnoText(errno));
  }
  ChildResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.error_text = ReadText(error_file);
  return result;
}

}  // namespace canalid::cli

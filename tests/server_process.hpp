#pragma once
// `ftctune serve` as a child process on an ephemeral loopback port, for crash-recovery tests.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace ftc::testing {

class ServerProcess {
 public:
  ServerProcess(const std::filesystem::path& store, const std::filesystem::path& log) {
    int out[2];
    if (::pipe(out) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, out[1], STDOUT_FILENO);
    posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND,
                                     0644);
    posix_spawn_file_actions_addclose(&fa, out[0]);
    const std::string store_s = store.string();
    std::vector<std::string> args = {FTC_CLI,   "serve", "--port",    "0",
                                     "--store", store_s, "--threads", "2"};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, FTC_CLI, &fa, nullptr, argv.data(), environ) != 0)
      throw std::runtime_error("cannot start ftctune serve");
    posix_spawn_file_actions_destroy(&fa);
    ::close(out[1]);
    // First line: "ftctune serve: listening on http://127.0.0.1:PORT (...)".
    std::string line;
    char c;
    while (::read(out[0], &c, 1) == 1 && c != '\n') line += c;
    ::close(out[0]);
    const auto colon = line.rfind(':', line.find(" (store"));
    if (line.find("listening on") == std::string::npos || colon == std::string::npos)
      throw std::runtime_error("server did not start: " + line);
    port_ = std::stoi(line.substr(colon + 1));
  }
  ~ServerProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  int port() const { return port_; }
  // Sends `sig` and returns the exit status (or -signal) once the process has ended.
  int signal_and_wait(int sig) {
    ::kill(pid_, sig);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
};

}  // namespace ftc::testing

#pragma once
// A private network namespace for tests of LCM's udpm (multicast) transport: its own loopback,
// brought up with the multicast route udpm needs, so a test neither depends on the host's routes
// nor sends a datagram outside its namespace.  As root the namespace is made directly (this also
// works inside a chroot, where a user namespace cannot be made); otherwise inside a user namespace
// (`unshare -r`).  A machine that allows neither cannot run these tests: they fail with the reason
// (PrivateNetworkProblem), never pass silently.
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "tests/support/child_process.h"

namespace canalid::testing {

/// argv prefix that runs a program as the first process of a new network namespace whose
/// loopback is up with the route 224.0.0.0/4 (append the program and its arguments).
inline std::vector<std::string> InNewPrivateNetwork() {
  const char* const script =
      "ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec \"$0\" \"$@\"";
  std::vector<std::string> argv = {"/usr/bin/unshare", geteuid() == 0 ? "-n" : "-rn", "sh", "-c",
                                   script};
  return argv;
}

/// argv prefix that runs a program in the network namespace of process `pid` (one started with
/// InNewPrivateNetwork()).
inline std::vector<std::string> InPrivateNetworkOf(pid_t pid) {
  if (geteuid() == 0) return {"/usr/bin/nsenter", "-n", "-t", std::to_string(pid)};
  return {"/usr/bin/nsenter", "--preserve-credentials", "-U", "-n", "-t", std::to_string(pid)};
}

/// Empty when a private network with a multicast route can be made here, else why not (missing
/// programs or no permission), for the test's failure message.
inline std::string PrivateNetworkProblem(const std::filesystem::path& scratch_dir) {
  for (const char* program : {"/usr/bin/unshare", "/usr/bin/nsenter"}) {
    if (!std::filesystem::exists(program)) {
      return std::string(program) + " is missing (Debian package util-linux)";
    }
  }
  if (!std::filesystem::exists("/usr/sbin/ip") && !std::filesystem::exists("/sbin/ip") &&
      !std::filesystem::exists("/bin/ip")) {
    return "ip is missing (Debian package iproute2)";
  }
  std::vector<std::string> probe = InNewPrivateNetwork();
  probe.push_back("/bin/true");
  ChildProcess child(probe, {}, scratch_dir / "private-network-probe.log");
  if (child.WaitExit(10000) != 0) {
    return "cannot make a private network namespace with a multicast route here (`" +
           std::string(geteuid() == 0 ? "unshare -n" : "unshare -rn") +
           "` then `ip route add 224.0.0.0/4 dev lo` failed: " + child.output() +
           "); run the tests as root or where user namespaces are allowed";
  }
  return {};
}

/// Moves this process into a new network namespace whose loopback is up with the route udpm
/// needs; the programs it starts afterwards share it, so the test, its servers and their clients
/// talk on a bus and ports of their own.  Call it first in the test, before any thread starts
/// (a user namespace, needed when not root, cannot be entered by a threaded process).  Empty on
/// success, else why it failed (the test fails with it).
inline std::string EnterPrivateNetwork() {
  const uid_t uid = geteuid();
  const gid_t gid = getegid();
  if (uid == 0) {
    if (unshare(CLONE_NEWNET) != 0) {
      return "unshare(CLONE_NEWNET): " + std::generic_category().message(errno) +
             " (a container without CAP_SYS_ADMIN?)";
    }
  } else {
    if (unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
      return "unshare(CLONE_NEWUSER | CLONE_NEWNET): " + std::generic_category().message(errno) +
             "; run the tests as root or where user namespaces are allowed";
    }
    for (const auto& [file, text] :
         {std::pair<const char*, std::string>{"/proc/self/setgroups", "deny"},
          {"/proc/self/uid_map", "0 " + std::to_string(uid) + " 1"},
          {"/proc/self/gid_map", "0 " + std::to_string(gid) + " 1"}}) {
      std::ofstream out(file);
      out << text;
      out.close();
      if (!out) return std::string("cannot write ") + file + " for the user namespace";
    }
  }
  ChildOptions options;
  options.argv = {"/bin/sh", "-c", "ip link set lo up && ip route add 224.0.0.0/4 dev lo"};
  ChildProcess ip(options);
  if (const int status = ip.WaitExit(10000); status != 0) {
    return "`ip link set lo up && ip route add 224.0.0.0/4 dev lo` failed in the new namespace "
           "(exit " +
           std::to_string(status) + ": " + ip.output() + "; Debian package iproute2)";
  }
  return {};
}

}  // namespace canalid::testing

// SPDX-License-Identifier: BSD-3-Clause
// VethHosts: `ip netns` and `ip link` commands, undone in reverse on destruction.
#include "tests/fastdds/veth_hosts.hpp"

#include <cstddef>
#include <initializer_list>

#include <unistd.h>

#include "tests/service/daemon_process.hpp"

namespace raymap::test {
namespace {

std::string findIp() {
  for (const char* path : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"}) {
    if (::access(path, X_OK) == 0) {
      return path;
    }
  }
  return {};
}

std::size_t index(VethHosts::Host host) { return host == VethHosts::Host::kRobot ? 0 : 1; }

}  // namespace

std::unique_ptr<VethHosts> VethHosts::create(std::string& why) {
  if (::geteuid() != 0) {
    why = "network namespaces need root";
    return nullptr;
  }
  std::unique_ptr<VethHosts> hosts(new VethHosts());
  hosts->ip_ = findIp();
  if (hosts->ip_.empty()) {
    why = "no ip program (install iproute2)";
    return nullptr;
  }
  const std::string id = std::to_string(::getpid());
  const std::string names[2] = {"raymap-robot-" + id, "raymap-planner-" + id};
  const std::string ends[2] = {"rmr" + id, "rmp" + id};  // interface names: at most 15 bytes
  const std::string addresses[2] = {"10.213.0.1/24", "10.213.0.2/24"};
  // Each step that fails leaves what was made so far to the destructor.
  const auto run = [&](std::initializer_list<std::string> args) {
    auto [status, output] = runToCompletion(hosts->ip_, std::vector<std::string>(args));
    if (status != 0) {
      why = "ip";
      for (const std::string& a : args) {
        why += " " + a;
      }
      why += ": " + output;
    }
    return status == 0;
  };
  for (std::size_t i = 0; i < 2; ++i) {
    if (!run({"netns", "add", names[i]})) {
      return nullptr;
    }
    hosts->namespaces_[i] = names[i];
  }
  if (!run({"link", "add", ends[0], "type", "veth", "peer", "name", ends[1]})) {
    return nullptr;
  }
  hosts->pair_ = ends[0];
  for (std::size_t i = 0; i < 2; ++i) {
    if (!run({"link", "set", ends[i], "netns", names[i]})) {
      return nullptr;
    }
    hosts->interfaces_[i] = ends[i];
    if (!run({"-n", names[i], "link", "set", "lo", "up"}) ||
        !run({"-n", names[i], "address", "add", addresses[i], "dev", ends[i]}) ||
        !run({"-n", names[i], "link", "set", ends[i], "multicast", "on", "up"}) ||
        !run({"-n", names[i], "route", "add", "default", "dev", ends[i]})) {
      return nullptr;
    }
  }
  return hosts;
}

VethHosts::~VethHosts() {
  // Deleting a namespace deletes the pair's end in it, and with it the other end; a pair that
  // never left this namespace (a failed step) is deleted here.
  if (!pair_.empty() && interfaces_[0].empty()) {
    runToCompletion(ip_, {"link", "delete", pair_});
  }
  for (const std::string& name : namespaces_) {
    if (!name.empty()) {
      runToCompletion(ip_, {"netns", "delete", name});
    }
  }
}

std::vector<std::string> VethHosts::launcher(Host host) const {
  return {ip_, "netns", "exec", namespaces_[index(host)]};
}

std::string VethHosts::interfaceOf(Host host) const { return interfaces_[index(host)]; }

}  // namespace raymap::test

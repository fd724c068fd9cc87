// Runtime registries by name (Aerial Gym's sim/env/robot/controller/task registries): register,
// list, make. Everything built in is registered through the same add() a user calls
// (register_builtins in registry.cpp), so a user's environment is a peer of "forest".
// Entries are factories returning a fresh config; the world is built from configs only.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

template <class T>
class Registry {
 public:
  using Factory = std::function<T()>;
  /// False (and nothing changed) if the name is taken or empty.
  bool add(const std::string& name, const std::string& description, Factory make) {
    if (name.empty() || entries_.count(name) != 0) return false;
    entries_[name] = Entry{description, std::move(make)};
    return true;
  }
  bool has(const std::string& name) const { return entries_.count(name) != 0; }
  /// Names in sorted order.
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& kv : entries_) out.push_back(kv.first);
    return out;
  }
  std::string description(const std::string& name) const {
    auto it = entries_.find(name);
    return it == entries_.end() ? std::string() : it->second.description;
  }
  /// False if unknown; `out` untouched.
  bool make(const std::string& name, T& out) const {
    auto it = entries_.find(name);
    if (it == entries_.end()) return false;
    out = it->second.make();
    return true;
  }
  /// "a, b, c" for error messages.
  std::string joined() const {
    std::string s;
    for (const auto& kv : entries_) s += (s.empty() ? "" : ", ") + kv.first;
    return s;
  }

 private:
  struct Entry {
    std::string description;
    Factory make;
  };
  std::map<std::string, Entry> entries_;
};

struct Registries {
  Registry<SimParams> sims;
  Registry<EnvConfig> envs;
  Registry<RobotConfig> robots;
  Registry<ControllerConfig> controllers;
  Registry<SensorConfig> sensors;
  Registry<TaskConfig> tasks;
  Registry<SimulatorConfig> simulators;  // physics backends (sim/simulator.hpp)
};

/// The process-wide registries, with the built-ins registered on first use.
Registries& registries();
/// Registers the built-ins into `r` (what registries() does once).
void register_builtins(Registries& r);

}  // namespace kestrel::sim

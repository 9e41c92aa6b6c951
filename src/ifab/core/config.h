#pragma once
/// \file
/// Typed, validated access to YAML configs. Every error names the file, the line, the field
/// path and what was expected, e.g.
///   data/sites/brick_stack.yaml:12: bricks[3].size: expected 3 positive numbers, got [0.24, -0.1, 0.05]
/// Options structs keep their brace-initialised defaults; a config only overrides what it names,
/// and unknown keys are rejected so that typos do not pass silently.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ifab/core/error.h"

namespace ifab {

class ConfigNode {
 public:
  /// Load a YAML file; throws InputError if it cannot be read or parsed.
  static ConfigNode LoadFile(const std::string& path);
  /// Load a YAML file whose top level holds `section` and nothing else (a misspelt or misplaced
  /// section would otherwise be ignored silently); returns that section.
  static ConfigNode LoadSection(const std::string& path, const char* section);
  /// Parse YAML text; `name` stands for the file in error messages.
  static ConfigNode FromString(const std::string& text, const std::string& name = "<string>");
  /// This config with `overlay` on top: maps merge key by key (recursively), anything else in
  /// the overlay replaces what is here. A partial user config thus changes only the keys it names
  /// on top of the shipped defaults. Messages name the overlay's file.
  ConfigNode Overlay(const ConfigNode& overlay) const;
  /// Apply `settings` ("a.b.c=VALUE", VALUE read as YAML: `mission.tilt_compensation=none`) in
  /// order, in place (nodes copied from this one see them; the rest keeps its file and line
  /// numbers, and relative paths their folder). Throws InputError naming the setting that is not
  /// KEY=VALUE or whose path runs through a non-map.
  void ApplySettings(const std::vector<std::string>& settings);
  /// The YAML text of this node.
  std::string Dump() const;

  bool IsMap() const { return node_.IsMap(); }
  bool IsSequence() const { return node_.IsSequence(); }
  bool IsNull() const { return !node_ || node_.IsNull(); }
  bool Has(const std::string& key) const;
  std::size_t size() const { return node_.size(); }

  /// Required child of a map; throws naming the missing key.
  ConfigNode operator[](const std::string& key) const;
  /// Child of a map if present.
  std::optional<ConfigNode> Find(const std::string& key) const;
  /// Element i of a sequence.
  ConfigNode operator[](std::size_t i) const;
  /// Keys of a map in file order.
  std::vector<std::string> Keys() const;

  /// Reject keys other than these (catches typos in configs).
  void ExpectKeys(std::initializer_list<const char*> allowed) const;
  /// Require that this node is a map / a sequence (of n elements when n >= 0).
  void ExpectMap() const;
  void ExpectSequence(int n = -1) const;

  /// This node's value as T (double, int, bool, std::string, std::uint64_t).
  template <typename T>
  T As() const;
  /// A sequence of exactly n numbers (any n when n < 0).
  std::vector<double> AsNumbers(int n = -1) const;
  Eigen::Vector3d AsVector3() const;

  /// Required field.
  template <typename T>
  T Get(const std::string& key) const {
    return (*this)[key].template As<T>();
  }
  /// Optional field with a default.
  template <typename T>
  T Get(const std::string& key, const T& fallback) const {
    auto c = Find(key);
    return c ? c->template As<T>() : fallback;
  }

  /// Overwrite `value` from `key` if present (keeps the Options default otherwise).
  template <typename T>
  void Read(const std::string& key, T& value) const {
    if (auto c = Find(key)) value = c->template As<T>();
  }
  /// Same, and require value > 0 / >= 0 / within [lo, hi]. An integer is a count that sizes
  /// something (beams, rollouts, bricks): it is also bounded above, by kMaxCount unless the
  /// field gives a tighter bound, so that a typo cannot ask for gigabytes.
  static constexpr int kMaxCount = 10'000'000;
  void ReadPositive(const std::string& key, double& value) const;
  void ReadPositive(const std::string& key, int& value, int hi = kMaxCount) const;
  void ReadNonNegative(const std::string& key, double& value) const;
  void ReadNonNegative(const std::string& key, int& value, int hi = kMaxCount) const;
  void ReadInRange(const std::string& key, double& value, double lo, double hi) const;
  void ReadInRange(const std::string& key, int& value, int lo, int hi) const;

  /// "file:line: field.path" for messages.
  std::string Where() const;
  const std::string& file() const { return *file_; }
  const std::string& path() const { return path_; }
  /// Throw InputError: "<where>: expected <expected>, got <this node's text>".
  [[noreturn]] void Fail(const std::string& expected) const;

  const YAML::Node& yaml() const { return node_; }

 private:
  ConfigNode(YAML::Node node, std::shared_ptr<const std::string> file, std::string path,
             int parent_line)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)),
        parent_line_(parent_line) {}
  std::string Text() const;
  int Line() const;

  YAML::Node node_;
  std::shared_ptr<const std::string> file_;
  std::string path_;
  int parent_line_{0};
};

}  // namespace ifab

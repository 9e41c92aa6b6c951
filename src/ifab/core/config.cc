#include "ifab/core/config.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>

namespace ifab {
namespace {

// A map key as text; a key that is itself a list or a map (`[a]: 1`) is no field name.
std::string KeyText(const YAML::Node& key, const std::string& file, const std::string& path) {
  if (!key.IsScalar())
    ThrowInputError("{}:{}: {}: expected field names, got a {} as a key", file, key.Mark().line + 1,
                    path.empty() ? "(top level)" : path, key.IsSequence() ? "list" : "map");
  return key.Scalar();
}

// YAML wants a map's keys unique; yaml-cpp keeps both and a lookup finds the first, so a key given
// twice (an edited copy, a pasted block) would silently read one value and drop the other.
void RejectDuplicateKeys(const YAML::Node& node, const std::string& file, const std::string& path) {
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) RejectDuplicateKeys(node[i], file, fmt::format("{}[{}]", path, i));
    return;
  }
  if (!node.IsMap()) return;
  std::map<std::string, int> first_line;
  for (const auto& kv : node) {
    if (!kv.first.IsScalar()) continue;  // KeyText says what is wrong with it when it is read
    const std::string key = kv.first.Scalar();
    const std::string at = path.empty() ? key : path + "." + key;
    const int line = kv.first.Mark().line + 1;
    if (const auto [it, inserted] = first_line.emplace(key, line); !inserted)
      ThrowInputError("{}:{}: {}: given twice (first on line {}); expected each key once", file, line, at, it->second);
    RejectDuplicateKeys(kv.second, file, at);
  }
}

}  // namespace

ConfigNode ConfigNode::LoadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) ThrowInputError("{}: cannot open the file", path);
  std::stringstream ss;
  ss << in.rdbuf();
  return FromString(ss.str(), path);
}

ConfigNode ConfigNode::LoadSection(const std::string& path, const char* section) {
  const ConfigNode root = LoadFile(path);
  root.ExpectKeys({section});
  return root[section];
}

ConfigNode ConfigNode::FromString(const std::string& text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    ThrowInputError("{}:{}: not valid YAML: {}", name, e.mark.line + 1, e.msg);
  }
  RejectDuplicateKeys(root, name, "");
  return ConfigNode(root, std::make_shared<const std::string>(name), "", 1);
}

namespace {

YAML::Node Merge(const YAML::Node& base, const YAML::Node& overlay) {
  if (!base.IsMap() || !overlay.IsMap()) return YAML::Clone(overlay);
  YAML::Node out = YAML::Clone(base);
  for (const auto& kv : overlay) {
    const std::string key = kv.first.as<std::string>();
    out[key] = out[key].IsDefined() ? Merge(out[key], kv.second) : YAML::Clone(kv.second);
  }
  return out;
}

}  // namespace

ConfigNode ConfigNode::Overlay(const ConfigNode& overlay) const {
  if (overlay.IsNull()) return *this;
  return ConfigNode(Merge(node_, overlay.node_),
                    std::make_shared<const std::string>(fmt::format("{} (over {})", *overlay.file_, *file_)), path_,
                    parent_line_);
}

void ConfigNode::ApplySettings(const std::vector<std::string>& settings) {
  YAML::Node root = node_;  // a handle: changes go to this config (a clone would lose the line marks)
  for (const std::string& s : settings) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0 || s.front() == '.' || s[eq - 1] == '.')
      ThrowInputError("--set '{}': expected KEY=VALUE, e.g. mission.tilt_compensation=none", s);
    std::vector<std::string> keys;
    for (std::size_t b = 0; b < eq;) {
      const std::size_t dot = std::min(s.find('.', b), eq);
      if (dot == b) ThrowInputError("--set '{}': an empty key between dots", s);
      keys.push_back(s.substr(b, dot - b));
      b = dot + 1;
    }
    YAML::Node value;
    try {
      value = YAML::Load(s.substr(eq + 1));
    } catch (const YAML::Exception& e) {
      ThrowInputError("--set '{}': the value is not valid YAML: {}", s, e.msg);
    }
    // Walk down by copies of the handles (assigning to a YAML::Node handle would rebind it).
    std::vector<YAML::Node> chain{root};
    for (std::size_t k = 0; k + 1 < keys.size(); ++k) {
      YAML::Node parent = chain.back();
      if (parent.IsDefined() && !parent.IsMap() && !parent.IsNull())
        ThrowInputError("--set '{}': '{}' is not a section (a map) in {}", s, keys[k], *file_);
      chain.push_back(parent[keys[k]]);
    }
    if (chain.back().IsDefined() && !chain.back().IsMap() && !chain.back().IsNull())
      ThrowInputError("--set '{}': the key's parent is not a section (a map) in {}", s, *file_);
    chain.back()[keys.back()] = value;
  }
}

std::string ConfigNode::Dump() const {
  YAML::Emitter out;
  out << node_;
  return out.c_str();
}

int ConfigNode::Line() const {
  if (node_ && !node_.Mark().is_null()) return node_.Mark().line + 1;
  return parent_line_;
}

std::string ConfigNode::Where() const {
  return fmt::format("{}:{}: {}", *file_, Line(), path_.empty() ? "(top level)" : path_);
}

std::string ConfigNode::Text() const {
  if (!node_ || node_.IsNull()) return "nothing";
  YAML::Emitter e;
  e.SetSeqFormat(YAML::Flow);
  e.SetMapFormat(YAML::Flow);
  e << node_;
  std::string s = e.c_str();
  if (s.size() > 80) s = s.substr(0, 77) + "...";
  return s;
}

void ConfigNode::Fail(const std::string& expected) const {
  ThrowInputError("{}: expected {}, got {}", Where(), expected, Text());
}

bool ConfigNode::Has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined();
}

std::optional<ConfigNode> ConfigNode::Find(const std::string& key) const {
  if (!node_.IsMap()) {
    if (IsNull()) return std::nullopt;
    Fail(fmt::format("a map with key '{}'", key));
  }
  const YAML::Node child = node_[key];
  if (!child.IsDefined()) return std::nullopt;
  return ConfigNode(child, file_, path_.empty() ? key : path_ + "." + key, Line());
}

ConfigNode ConfigNode::operator[](const std::string& key) const {
  auto c = Find(key);
  if (!c) {
    const std::string full = path_.empty() ? key : path_ + "." + key;
    ThrowInputError("{}:{}: {}: required field is missing", *file_, Line(), full);
  }
  return *c;
}

ConfigNode ConfigNode::operator[](std::size_t i) const {
  ExpectSequence();
  IFAB_THROW_UNLESS(i < node_.size(), "{}: expected at least {} elements, got {}", Where(), i + 1,
                    node_.size());
  return ConfigNode(node_[i], file_, fmt::format("{}[{}]", path_, i), Line());
}

std::vector<std::string> ConfigNode::Keys() const {
  std::vector<std::string> keys;
  if (!node_.IsMap()) return keys;
  for (const auto& kv : node_) keys.push_back(KeyText(kv.first, *file_, path_));
  return keys;
}

void ConfigNode::ExpectKeys(std::initializer_list<const char*> allowed) const {
  if (IsNull()) return;
  ExpectMap();
  for (const auto& kv : node_) {
    const std::string key = KeyText(kv.first, *file_, path_);
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a;
    if (!ok) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      ThrowInputError("{}:{}: {}: unknown field (expected one of: {})", *file_,
                      kv.first.Mark().line + 1, path_.empty() ? key : path_ + "." + key, list);
    }
  }
}

void ConfigNode::ExpectMap() const {
  if (!node_.IsMap()) Fail("a map");
}

void ConfigNode::ExpectSequence(int n) const {
  if (!node_.IsSequence()) Fail(n >= 0 ? fmt::format("a list of {} elements", n) : "a list");
  if (n >= 0 && static_cast<int>(node_.size()) != n) Fail(fmt::format("a list of {} elements", n));
}

template <>
double ConfigNode::As<double>() const {
  if (!node_.IsScalar()) Fail("a number");
  double v = 0.0;
  if (!YAML::convert<double>::decode(node_, v) || !std::isfinite(v)) Fail("a number");
  return v;
}

template <>
int ConfigNode::As<int>() const {
  if (!node_.IsScalar()) Fail("an integer");
  int v = 0;
  if (!YAML::convert<int>::decode(node_, v)) Fail("an integer");
  return v;
}

template <>
std::uint64_t ConfigNode::As<std::uint64_t>() const {
  if (!node_.IsScalar()) Fail("a non-negative integer");
  std::uint64_t v = 0;
  if (!node_.Scalar().empty() && node_.Scalar()[0] == '-') Fail("a non-negative integer");
  if (!YAML::convert<std::uint64_t>::decode(node_, v)) Fail("a non-negative integer");
  return v;
}

template <>
bool ConfigNode::As<bool>() const {
  if (!node_.IsScalar()) Fail("true or false");
  bool v = false;
  if (!YAML::convert<bool>::decode(node_, v)) Fail("true or false");
  return v;
}

template <>
std::string ConfigNode::As<std::string>() const {
  if (!node_.IsScalar()) Fail("a string");
  return node_.Scalar();
}

std::vector<double> ConfigNode::AsNumbers(int n) const {
  const std::string what = n >= 0 ? fmt::format("a list of {} numbers", n) : "a list of numbers";
  if (!node_.IsSequence() || (n >= 0 && static_cast<int>(node_.size()) != n)) Fail(what);
  std::vector<double> out;
  for (const auto& e : node_) {
    double v = 0.0;
    if (!e.IsScalar() || !YAML::convert<double>::decode(e, v) || !std::isfinite(v)) Fail(what);
    out.push_back(v);
  }
  return out;
}

Eigen::Vector3d ConfigNode::AsVector3() const {
  const auto v = AsNumbers(3);
  return {v[0], v[1], v[2]};
}

void ConfigNode::ReadPositive(const std::string& key, double& value) const {
  if (auto c = Find(key)) {
    value = c->As<double>();
    if (!(value > 0.0)) c->Fail("a positive number");
  }
}
void ConfigNode::ReadPositive(const std::string& key, int& value, int hi) const {
  ReadInRange(key, value, 1, hi);
}
void ConfigNode::ReadNonNegative(const std::string& key, double& value) const {
  if (auto c = Find(key)) {
    value = c->As<double>();
    if (value < 0.0) c->Fail("a number >= 0");
  }
}
void ConfigNode::ReadNonNegative(const std::string& key, int& value, int hi) const {
  ReadInRange(key, value, 0, hi);
}
void ConfigNode::ReadInRange(const std::string& key, int& value, int lo, int hi) const {
  if (auto c = Find(key)) {
    value = c->As<int>();
    if (value < lo || value > hi) {
      if (lo == 1) c->Fail(fmt::format("a positive integer (at most {})", hi));
      if (lo == 0) c->Fail(fmt::format("an integer >= 0 (at most {})", hi));
      c->Fail(fmt::format("an integer in [{}, {}]", lo, hi));
    }
  }
}
void ConfigNode::ReadInRange(const std::string& key, double& value, double lo, double hi) const {
  if (auto c = Find(key)) {
    value = c->As<double>();
    if (value < lo || value > hi) c->Fail(fmt::format("a number in [{}, {}]", lo, hi));
  }
}

}  // namespace ifab

#include "ifab/perception/ply.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <istream>
#include <limits>
#include <optional>
#include <ostream>
#include <sstream>
#include <vector>

#include "ifab/core/error.h"

namespace ifab {
namespace {

enum class Type { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<Type> ParseType(const std::string& s) {
  if (s == "char" || s == "int8") return Type::kInt8;
  if (s == "uchar" || s == "uint8") return Type::kUint8;
  if (s == "short" || s == "int16") return Type::kInt16;
  if (s == "ushort" || s == "uint16") return Type::kUint16;
  if (s == "int" || s == "int32") return Type::kInt32;
  if (s == "uint" || s == "uint32") return Type::kUint32;
  if (s == "float" || s == "float32") return Type::kFloat32;
  if (s == "double" || s == "float64") return Type::kFloat64;
  return std::nullopt;
}

std::size_t SizeOf(Type t) {
  switch (t) {
    case Type::kInt8: case Type::kUint8: return 1;
    case Type::kInt16: case Type::kUint16: return 2;
    case Type::kInt32: case Type::kUint32: case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 0;
}

struct Property {
  std::string name;
  Type type{Type::kFloat32};
  bool is_list{false};
  Type count_type{Type::kUint8};
};

struct Element {
  std::string name;
  std::uint64_t count{0};
  std::vector<Property> properties;
};

// Reads values of PLY types from the body, ASCII or binary.
class BodyReader {
 public:
  BodyReader(std::istream& in, PlyFormat format, const std::string& name) : in_(in), format_(format), name_(name) {}

  // Returns nullopt at the end of the data.
  std::optional<double> Read(Type type) {
    if (format_ == PlyFormat::kAscii) {
      std::string token;
      if (!(in_ >> token)) return std::nullopt;
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') ThrowInputError("{}: '{}' is not a number{}", name_, token, where_);
      return v;
    }
    unsigned char bytes[8];
    const std::size_t n = SizeOf(type);
    if (!in_.read(reinterpret_cast<char*>(bytes), static_cast<std::streamsize>(n))) return std::nullopt;
    const bool file_little = format_ == PlyFormat::kBinaryLittleEndian;
    if (file_little != (std::endian::native == std::endian::little)) std::reverse(bytes, bytes + n);
    switch (type) {
      case Type::kInt8: { std::int8_t v; std::memcpy(&v, bytes, 1); return v; }
      case Type::kUint8: { std::uint8_t v; std::memcpy(&v, bytes, 1); return v; }
      case Type::kInt16: { std::int16_t v; std::memcpy(&v, bytes, 2); return v; }
      case Type::kUint16: { std::uint16_t v; std::memcpy(&v, bytes, 2); return v; }
      case Type::kInt32: { std::int32_t v; std::memcpy(&v, bytes, 4); return v; }
      case Type::kUint32: { std::uint32_t v; std::memcpy(&v, bytes, 4); return v; }
      case Type::kFloat32: { float v; std::memcpy(&v, bytes, 4); return v; }
      case Type::kFloat64: { double v; std::memcpy(&v, bytes, 8); return v; }
    }
    return std::nullopt;
  }

  void SetWhere(std::string where) { where_ = std::move(where); }
  const std::string& where() const { return where_; }

 private:
  std::istream& in_;
  PlyFormat format_;
  const std::string& name_;
  std::string where_;
};

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  return s;
}

}  // namespace

PointCloud ReadPly(std::istream& in, const std::string& name) {
  std::string line;
  int line_no = 0;
  auto next_line = [&]() -> bool {
    if (!std::getline(in, line)) return false;
    line = Trim(line);
    ++line_no;
    return true;
  };
  if (!next_line() || line != "ply") ThrowInputError("{}: not a PLY file (the first line must be 'ply')", name);

  std::optional<PlyFormat> format;
  std::vector<Element> elements;
  bool ended = false;
  while (next_line()) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      ended = true;
      break;
    }
    if (keyword == "format") {
      std::string f, version;
      words >> f >> version;
      if (f == "ascii") format = PlyFormat::kAscii;
      else if (f == "binary_little_endian") format = PlyFormat::kBinaryLittleEndian;
      else if (f == "binary_big_endian") format = PlyFormat::kBinaryBigEndian;
      else ThrowInputError("{}: line {}: unknown format '{}' (expected ascii, binary_little_endian or binary_big_endian)", name, line_no, f);
    } else if (keyword == "element") {
      Element e;
      std::string count;
      words >> e.name >> count;
      char* end = nullptr;
      errno = 0;
      const long long c = std::strtoll(count.c_str(), &end, 10);
      if (e.name.empty() || count.empty() || *end != '\0' || c < 0 || errno == ERANGE)
        ThrowInputError("{}: line {}: expected 'element <name> <count>' with a count >= 0 (at most {}), got '{}'",
                        name, line_no, std::numeric_limits<long long>::max(), line);
      e.count = static_cast<std::uint64_t>(c);
      elements.push_back(e);
    } else if (keyword == "property") {
      if (elements.empty()) ThrowInputError("{}: line {}: property before any element", name, line_no);
      Property p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        const auto ct = ParseType(count_type), it = ParseType(item_type);
        if (!ct || !it) ThrowInputError("{}: line {}: unknown type in '{}'", name, line_no, line);
        p.is_list = true;
        p.count_type = *ct;
        p.type = *it;
      } else {
        words >> p.name;
        const auto t = ParseType(type);
        if (!t) ThrowInputError("{}: line {}: unknown property type '{}' (expected char, uchar, short, ushort, int, uint, float or double)", name, line_no, type);
        p.type = *t;
      }
      if (p.name.empty()) ThrowInputError("{}: line {}: property without a name", name, line_no);
      elements.back().properties.push_back(p);
    } else {
      ThrowInputError("{}: line {}: unexpected header line '{}'", name, line_no, line);
    }
  }
  if (!ended) ThrowInputError("{}: the header has no 'end_header'", name);
  if (!format) ThrowInputError("{}: the header has no 'format' line", name);
  // An instance without properties takes no bytes: a huge count of them would loop for ever.
  for (const auto& e : elements)
    if (e.properties.empty() && e.count > 0)
      ThrowInputError("{}: element '{}' declares {} instances but no properties", name, e.name, e.count);

  PointCloud cloud;
  BodyReader body(in, *format, name);
  // A list's length: a whole number in its count type's range (a cast from a negative, fractional
  // or NaN value would be undefined); nullopt at the end of the data.
  auto read_list_count = [&](const Property& p) -> std::optional<std::uint64_t> {
    const auto c = body.Read(p.count_type);
    if (!c) return std::nullopt;
    const double max_count = std::ldexp(1.0, 8 * static_cast<int>(SizeOf(p.count_type)));
    if (!(*c >= 0.0 && *c < max_count && std::floor(*c) == *c))
      ThrowInputError("{}: list '{}' has length {}, expected a whole number from 0 to {}{}", name, p.name, *c,
                      max_count - 1, body.where());
    return static_cast<std::uint64_t>(*c);
  };
  auto skip_instance = [&](const Element& e, std::uint64_t index) {
    for (const auto& p : e.properties) {
      body.SetWhere(fmt::format(" ({} {}, property {})", e.name, index, p.name));
      std::uint64_t n = 1;
      if (p.is_list) {
        const auto c = read_list_count(p);
        if (!c) return false;
        n = *c;
      }
      for (std::uint64_t k = 0; k < n; ++k)
        if (!body.Read(p.type)) return false;
    }
    return true;
  };
  bool have_vertex = false;
  for (const auto& e : elements) {
    if (e.name != "vertex") {
      for (std::uint64_t i = 0; i < e.count; ++i)
        if (!skip_instance(e, i)) ThrowInputError("{}: the data ends inside element '{}' ({} of {})", name, e.name, i, e.count);
      continue;
    }
    have_vertex = true;
    int ix = -1, iy = -1, iz = -1;
    std::vector<int> field_of(e.properties.size(), -1);
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (p.is_list) continue;
      if (p.name == "x") ix = static_cast<int>(k);
      else if (p.name == "y") iy = static_cast<int>(k);
      else if (p.name == "z") iz = static_cast<int>(k);
      else {
        field_of[k] = static_cast<int>(cloud.fields.size());
        cloud.fields.push_back({p.name, {}});
      }
    }
    if (ix < 0 || iy < 0 || iz < 0) ThrowInputError("{}: element 'vertex' needs scalar properties x, y and z", name);
    if (e.count > 200'000'000) ThrowInputError("{}: {} vertices is more than this reader accepts", name, e.count);
    // Reserve no more than a modest block up front: the count is the file's claim, not its size,
    // and a 100-byte file must not be able to ask for gigabytes.
    const std::size_t reserve = static_cast<std::size_t>(std::min<std::uint64_t>(e.count, 1u << 16));
    cloud.points.reserve(reserve);
    for (auto& f : cloud.fields) f.values.reserve(reserve);
    std::vector<double> values(e.properties.size());
    for (std::uint64_t i = 0; i < e.count; ++i) {
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const Property& p = e.properties[k];
        body.SetWhere(fmt::format(" (vertex {}, property {})", i, p.name));
        if (p.is_list) {
          const auto c = read_list_count(p);
          bool ok = c.has_value();
          for (std::uint64_t j = 0; ok && j < *c; ++j) ok = body.Read(p.type).has_value();
          if (!ok) ThrowInputError("{}: the header declares {} vertices, the data ends at vertex {}", name, e.count, i);
          continue;
        }
        const auto v = body.Read(p.type);
        if (!v) ThrowInputError("{}: the header declares {} vertices, the data ends at vertex {}", name, e.count, i);
        // NaN or infinity is no measurement; downstream solvers would carry it into every sum.
        if (!std::isfinite(*v))
          ThrowInputError("{}: vertex {}, property {}: expected a finite number, got {}", name, i, p.name, *v);
        values[k] = *v;
      }
      cloud.points.emplace_back(values[static_cast<std::size_t>(ix)], values[static_cast<std::size_t>(iy)],
                                values[static_cast<std::size_t>(iz)]);
      for (std::size_t k = 0; k < e.properties.size(); ++k)
        if (field_of[k] >= 0) cloud.fields[static_cast<std::size_t>(field_of[k])].values.push_back(values[k]);
    }
    break;  // later elements (faces) are not needed
  }
  if (!have_vertex) ThrowInputError("{}: no 'vertex' element", name);
  return cloud;
}

PointCloud ReadPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowInputError("{}: cannot open for reading", path);
  return ReadPly(in, path);
}

void WritePly(std::ostream& out, const PointCloud& cloud, const PlyWriteOptions& options) {
  for (const auto& f : cloud.fields)
    IFAB_CHECK(f.values.size() == cloud.points.size());
  const char* format = options.format == PlyFormat::kAscii                ? "ascii"
                       : options.format == PlyFormat::kBinaryLittleEndian ? "binary_little_endian"
                                                                          : "binary_big_endian";
  const char* type = options.double_precision ? "double" : "float";
  out << "ply\nformat " << format << " 1.0\n";
  if (!options.comment.empty()) out << "comment " << options.comment << "\n";
  out << "comment written by ifab\n";
  out << "element vertex " << cloud.points.size() << "\n";
  for (const char* axis : {"x", "y", "z"}) out << "property " << type << " " << axis << "\n";
  for (const auto& f : cloud.fields) out << "property " << type << " " << f.name << "\n";
  out << "end_header\n";
  const bool swap = (options.format == PlyFormat::kBinaryLittleEndian) != (std::endian::native == std::endian::little);
  auto put = [&](double v) {
    if (options.format == PlyFormat::kAscii) {
      out << (options.double_precision ? fmt::format("{:.17g}", v) : fmt::format("{:.9g}", v));
      return;
    }
    unsigned char bytes[8];
    std::size_t n = 8;
    if (options.double_precision) {
      std::memcpy(bytes, &v, 8);
    } else {
      const float f = static_cast<float>(v);
      std::memcpy(bytes, &f, 4);
      n = 4;
    }
    if (swap) std::reverse(bytes, bytes + n);
    out.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(n));
  };
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (k > 0 && options.format == PlyFormat::kAscii) out << ' ';
      put(cloud.points[i][k]);
    }
    for (const auto& f : cloud.fields) {
      if (options.format == PlyFormat::kAscii) out << ' ';
      put(f.values[i]);
    }
    if (options.format == PlyFormat::kAscii) out << '\n';
  }
}

}  // namespace ifab

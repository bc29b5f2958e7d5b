#include "semap/io/ply_io.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/text_util.hpp"

namespace semap {

namespace {

// ---------------------------------------------------------------- writing

template <class T>
void append_le(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}


// ---------------------------------------------------------------- reading

enum class Format { kAscii, kBinaryLittle, kBinaryBig };

enum class Scalar { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<Scalar> scalar_from_name(std::string_view name) {
  if (name == "char" || name == "int8") return Scalar::kInt8;
  if (name == "uchar" || name == "uint8") return Scalar::kUint8;
  if (name == "short" || name == "int16") return Scalar::kInt16;
  if (name == "ushort" || name == "uint16") return Scalar::kUint16;
  if (name == "int" || name == "int32") return Scalar::kInt32;
  if (name == "uint" || name == "uint32") return Scalar::kUint32;
  if (name == "float" || name == "float32") return Scalar::kFloat32;
  if (name == "double" || name == "float64") return Scalar::kFloat64;
  return std::nullopt;
}

size_t scalar_size(Scalar s) {
  switch (s) {
    case Scalar::kInt8: case Scalar::kUint8: return 1;
    case Scalar::kInt16: case Scalar::kUint16: return 2;
    case Scalar::kInt32: case Scalar::kUint32: case Scalar::kFloat32: return 4;
    case Scalar::kFloat64: return 8;
  }
  return 1;
}

/// Clamps into [0, hi]; NaN/Inf from a corrupt file become 0 (casting them is undefined).
double clamp_finite(double v, double hi) { return std::isfinite(v) ? std::clamp(v, 0.0, hi) : 0.0; }

/// A label value as read, for an error message: integers without a fraction, others as %g.
std::string format_label_value(double v) {
  if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e15) return std::to_string(static_cast<int64_t>(v));
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

bool is_integer(Scalar s) { return s != Scalar::kFloat32 && s != Scalar::kFloat64; }

struct Property {
  std::string name;
  Scalar type = Scalar::kFloat32;
  bool is_list = false;
  Scalar count_type = Scalar::kUint8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  /// Smallest possible size of one record in bytes (lists count as empty).
  size_t min_binary_size() const {
    size_t s = 0;
    for (const auto& p : properties) s += p.is_list ? scalar_size(p.count_type) : scalar_size(p.type);
    return s;
  }
};

/// Bounds-checked reader of the data section; every value comes back as a double.
class DataCursor {
 public:
  DataCursor(const std::string& path, std::string_view data, Format format)
      : path_(path), data_(data), format_(format) {}

  size_t remaining() const { return data_.size() - pos_; }

  double read(Scalar type) { return format_ == Format::kAscii ? read_ascii(type) : read_binary(type); }

 private:
  template <class T>
  double decode() {
    T value;
    char bytes[sizeof(T)];
    std::memcpy(bytes, data_.data() + pos_, sizeof(T));
    const bool swap = (format_ == Format::kBinaryBig) != (std::endian::native == std::endian::big);
    if (swap) std::reverse(bytes, bytes + sizeof(T));
    std::memcpy(&value, bytes, sizeof(T));
    pos_ += sizeof(T);
    return static_cast<double>(value);
  }

  double read_binary(Scalar type) {
    if (remaining() < scalar_size(type)) throw Error(path_, "truncated data (file ends inside an element)");
    switch (type) {
      case Scalar::kInt8: return decode<int8_t>();
      case Scalar::kUint8: return decode<uint8_t>();
      case Scalar::kInt16: return decode<int16_t>();
      case Scalar::kUint16: return decode<uint16_t>();
      case Scalar::kInt32: return decode<int32_t>();
      case Scalar::kUint32: return decode<uint32_t>();
      case Scalar::kFloat32: return decode<float>();
      case Scalar::kFloat64: return decode<double>();
    }
    return 0.0;
  }

  double read_ascii(Scalar type) {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    if (pos_ >= data_.size()) throw Error(path_, "truncated data (fewer values than the header declares)");
    size_t end = pos_;
    while (end < data_.size() && !std::isspace(static_cast<unsigned char>(data_[end]))) ++end;
    const auto value = io_detail::parse_double(data_.substr(pos_, end - pos_));
    if (!value) throw Error(path_, "malformed number '" + std::string(data_.substr(pos_, std::min<size_t>(end - pos_, 32))) + "' in data");
    pos_ = end;
    if (is_integer(type) && *value != std::floor(*value))
      throw Error(path_, "non-integer value for an integer property");
    return *value;
  }

  std::string path_;
  std::string_view data_;
  Format format_;
  size_t pos_ = 0;
};

struct Header {
  Format format = Format::kAscii;
  std::vector<Element> elements;
  size_t data_offset = 0;
};

Header parse_header(const std::string& path, const std::string& bytes) {
  // A header is text; cap its size so garbage never makes us scan a huge file line by line.
  constexpr size_t kMaxHeaderBytes = 1 << 20;
  Header header;
  size_t pos = 0, line_no = 0;
  bool have_format = false;
  auto next_line = [&](std::string_view& line) {
    if (pos >= bytes.size() || pos > kMaxHeaderBytes) return false;
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) return false;
    line = std::string_view(bytes).substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = end + 1;
    ++line_no;
    return true;
  };
  std::string_view line;
  if (!next_line(line) || line != "ply") throw Error(path, "not a PLY file (missing 'ply' magic)");
  while (true) {
    if (!next_line(line)) throw Error(path, "PLY header without 'end_header'");
    const auto f = io_detail::split_fields(line);
    const std::string where = path + ": header line " + std::to_string(line_no);
    if (f.empty()) continue;
    if (f[0] == "end_header") break;
    if (f[0] == "comment" || f[0] == "obj_info") continue;
    if (f[0] == "format") {
      if (f.size() < 2) throw Error(where, "malformed format line");
      if (f[1] == "ascii") header.format = Format::kAscii;
      else if (f[1] == "binary_little_endian") header.format = Format::kBinaryLittle;
      else if (f[1] == "binary_big_endian") header.format = Format::kBinaryBig;
      else throw Error(where, "unsupported PLY format '" + std::string(f[1]) + "'");
      have_format = true;
    } else if (f[0] == "element") {
      if (f.size() != 3) throw Error(where, "malformed element line");
      Element e;
      e.name = std::string(f[1]);
      const auto [ptr, ec] = std::from_chars(f[2].data(), f[2].data() + f[2].size(), e.count);
      if (ec != std::errc() || ptr != f[2].data() + f[2].size()) throw Error(where, "malformed element count");
      header.elements.push_back(std::move(e));
    } else if (f[0] == "property") {
      if (header.elements.empty()) throw Error(where, "property before any element");
      Property p;
      if (f.size() == 5 && f[1] == "list") {
        const auto count_type = scalar_from_name(f[2]);
        const auto item_type = scalar_from_name(f[3]);
        if (!count_type || !item_type || !is_integer(*count_type))
          throw Error(where, "unsupported list property types");
        p.is_list = true;
        p.count_type = *count_type;
        p.type = *item_type;
        p.name = std::string(f[4]);
      } else if (f.size() == 3) {
        const auto type = scalar_from_name(f[1]);
        if (!type) throw Error(where, "unknown property type '" + std::string(f[1]) + "'");
        p.type = *type;
        p.name = std::string(f[2]);
      } else {
        throw Error(where, "malformed property line");
      }
      header.elements.back().properties.push_back(std::move(p));
    } else {
      throw Error(where, "unknown header keyword '" + std::string(f[0].substr(0, 32)) + "'");
    }
  }
  if (!have_format) throw Error(path, "PLY header without a format line");
  header.data_offset = pos;
  return header;
}

}  // namespace

std::string encode_ply(const TriangleMesh& mesh, const std::filesystem::path& path) {
  const PointCloud& c = mesh.vertices;
  if (!c.consistent()) throw Error(path, "point cloud attributes differ in size from the points");
  const size_t n = c.size();
  for (const auto& t : mesh.triangles)
    for (uint32_t index : t)
      if (index >= n) throw Error(path, "triangle index " + std::to_string(index) + " out of range");

  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by semap\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (c.has_normals()) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (c.has_colours()) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (c.has_labels()) out += "property uchar label\n";
  if (c.has_instances()) out += "property uint instance\n";
  if (!mesh.triangles.empty())
    out += "element face " + std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\n";
  out += "end_header\n";

  const size_t record = 12 + (c.has_normals() ? 12 : 0) + (c.has_colours() ? 3 : 0) + (c.has_labels() ? 1 : 0) +
                        (c.has_instances() ? 4 : 0);
  out.reserve(out.size() + n * record + mesh.triangles.size() * 13);
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) append_le<float>(out, c.points[i][k]);
    if (c.has_normals())
      for (int k = 0; k < 3; ++k) append_le<float>(out, c.normals[i][k]);
    if (c.has_colours()) {
      append_le<uint8_t>(out, c.colours[i].r);
      append_le<uint8_t>(out, c.colours[i].g);
      append_le<uint8_t>(out, c.colours[i].b);
    }
    if (c.has_labels()) append_le<uint8_t>(out, c.labels[i]);
    if (c.has_instances()) append_le<uint32_t>(out, c.instances[i]);
  }
  for (const auto& t : mesh.triangles) {
    append_le<uint8_t>(out, 3);
    for (uint32_t index : t) append_le<int32_t>(out, static_cast<int32_t>(index));
  }
  return out;
}

void write_ply(const std::filesystem::path& path, const PointCloud& cloud) {
  TriangleMesh mesh;
  mesh.vertices = cloud;
  write_ply(path, mesh);
}

void write_ply(const std::filesystem::path& path, const TriangleMesh& mesh) {
  write_file_atomic(path, encode_ply(mesh, path));
}

TriangleMesh read_ply(const std::filesystem::path& file) {
  return parse_ply(io_detail::read_file_bytes(file, kMaxMeshFileBytes, "PLY file"), file.string());
}

TriangleMesh parse_ply(const std::string& bytes, const std::string& path) {
  const Header header = parse_header(path, bytes);
  DataCursor cursor(path, std::string_view(bytes).substr(header.data_offset), header.format);

  TriangleMesh mesh;
  PointCloud& cloud = mesh.vertices;
  bool have_vertices = false;
  for (const Element& element : header.elements) {
    if (element.properties.empty() || element.count == 0) continue;  // nothing stored
    // A lying header must not make us allocate: every record needs at least this many bytes.
    const size_t min_size = header.format == Format::kAscii ? 2 * element.properties.size()
                                                              : element.min_binary_size();
    if (element.count > cursor.remaining() / std::max<size_t>(min_size, 1) + 1)
      throw Error(path, "truncated data: header declares " + std::to_string(element.count) + " '" + element.name +
                            "' elements, more than the file holds");

    const bool is_vertex = element.name == "vertex";
    const bool is_face = element.name == "face";
    // Which property feeds which attribute (-1 = absent).
    auto index_of = [&](std::initializer_list<std::string_view> names) {
      for (size_t k = 0; k < element.properties.size(); ++k)
        for (auto n : names)
          if (!element.properties[k].is_list && element.properties[k].name == n) return static_cast<int>(k);
      return -1;
    };
    int xyz[3] = {-1, -1, -1}, nrm[3] = {-1, -1, -1}, rgb[3] = {-1, -1, -1}, label = -1, instance = -1;
    int face_list = -1;
    if (is_vertex) {
      if (have_vertices) throw Error(path, "more than one vertex element");
      have_vertices = true;
      xyz[0] = index_of({"x"}), xyz[1] = index_of({"y"}), xyz[2] = index_of({"z"});
      if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) throw Error(path, "vertex element without x y z");
      nrm[0] = index_of({"nx"}), nrm[1] = index_of({"ny"}), nrm[2] = index_of({"nz"});
      rgb[0] = index_of({"red", "diffuse_red", "r"}), rgb[1] = index_of({"green", "diffuse_green", "g"});
      rgb[2] = index_of({"blue", "diffuse_blue", "b"});
      label = index_of({"label"});
      instance = index_of({"instance"});
      const size_t n = element.count;
      cloud.points.resize(n);
      if (nrm[0] >= 0 && nrm[1] >= 0 && nrm[2] >= 0) cloud.normals.resize(n);
      if (rgb[0] >= 0 && rgb[1] >= 0 && rgb[2] >= 0) cloud.colours.resize(n);
      if (label >= 0) cloud.labels.resize(n);
      if (instance >= 0) cloud.instances.resize(n);
    }
    if (is_face) {
      for (size_t k = 0; k < element.properties.size(); ++k)
        if (element.properties[k].is_list &&
            (element.properties[k].name == "vertex_indices" || element.properties[k].name == "vertex_index"))
          face_list = static_cast<int>(k);
      mesh.triangles.reserve(element.count);
    }

    std::vector<double> values(element.properties.size());
    std::vector<int64_t> polygon;
    for (uint64_t i = 0; i < element.count; ++i) {
      for (size_t k = 0; k < element.properties.size(); ++k) {
        const Property& p = element.properties[k];
        if (!p.is_list) {
          values[k] = cursor.read(p.type);
          continue;
        }
        const double count = cursor.read(p.count_type);
        if (count < 0 || count > static_cast<double>(cursor.remaining()))
          throw Error(path, "corrupt list length in element '" + element.name + "'");
        const size_t n = static_cast<size_t>(count);
        const bool keep = static_cast<int>(k) == face_list;
        if (keep) polygon.resize(n);
        for (size_t j = 0; j < n; ++j) {
          const double v = cursor.read(p.type);
          if (keep) {
            if (!(v >= 0 && v < 4294967295.0)) throw Error(path, "face " + std::to_string(i) + ": invalid vertex index");
            polygon[j] = static_cast<int64_t>(v);
          }
        }
        if (keep) {
          if (n < 3) throw Error(path, "face " + std::to_string(i) + " has fewer than 3 vertices");
          for (size_t j = 1; j + 1 < n; ++j)  // fan-triangulate polygons
            mesh.triangles.push_back({static_cast<uint32_t>(polygon[0]), static_cast<uint32_t>(polygon[j]),
                                      static_cast<uint32_t>(polygon[j + 1])});
        }
      }
      if (!is_vertex) continue;
      auto to_u8 = [&](int k) {
        double v = values[k];
        if (!is_integer(element.properties[k].type)) v *= 255.0;  // float colours are 0..1
        return static_cast<uint8_t>(clamp_finite(std::round(v), 255.0));
      };
      cloud.points[i] = {static_cast<float>(values[xyz[0]]), static_cast<float>(values[xyz[1]]),
                         static_cast<float>(values[xyz[2]])};
      if (cloud.has_normals())
        cloud.normals[i] = {static_cast<float>(values[nrm[0]]), static_cast<float>(values[nrm[1]]),
                            static_cast<float>(values[nrm[2]])};
      if (cloud.has_colours()) cloud.colours[i] = {to_u8(rgb[0]), to_u8(rgb[1]), to_u8(rgb[2])};
      if (cloud.has_labels()) {
        // A label a ClassId cannot hold is an error, not a silent 255 (issue 44, class 8).
        const double v = values[label];
        if (!(v >= 0.0 && v <= 255.0 && v == std::floor(v)))
          throw Error(path, "vertex " + std::to_string(i) + ": label " + format_label_value(v) +
                                " is not a class id (0..255)");
        cloud.labels[i] = static_cast<ClassId>(v);
      }
      if (cloud.has_instances()) cloud.instances[i] = static_cast<uint32_t>(clamp_finite(values[instance], 4294967295.0));
    }
  }
  for (const auto& t : mesh.triangles)
    for (uint32_t index : t)
      if (index >= cloud.size())
        throw Error(path, "face refers to vertex " + std::to_string(index) + " but there are only " +
                              std::to_string(cloud.size()));
  return mesh;
}

}  // namespace semap

#include "segmentation/onnx_model_info.hpp"

#include <fstream>
#include <iterator>
#include <set>

#include "semap/core/error.hpp"
#include "core/paths.hpp"

namespace semap {
namespace {

// Protobuf wire format: each field is a varint key (field << 3 | wire type) then its value.
struct Reader {
  const uint8_t* p;
  const uint8_t* end;
  bool ok = true;

  bool done() const { return p >= end || !ok; }
  uint64_t varint() {
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (p >= end) { ok = false; return 0; }
      const uint8_t b = *p++;
      v |= uint64_t(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    ok = false;
    return 0;
  }
  // Returns a sub-reader for a length-delimited field.
  Reader bytes() {
    const uint64_t n = varint();
    if (!ok || n > uint64_t(end - p)) { ok = false; return {end, end, false}; }
    Reader r{p, p + n};
    p += n;
    return r;
  }
  void skip(int wire_type) {
    switch (wire_type) {
      case 0: varint(); break;
      case 1: if (end - p < 8) ok = false; else p += 8; break;
      case 2: bytes(); break;
      case 5: if (end - p < 4) ok = false; else p += 4; break;
      default: ok = false;
    }
  }
  std::string str() {
    Reader r = bytes();
    return ok ? std::string(reinterpret_cast<const char*>(r.p), r.end - r.p) : std::string{};
  }
};

// TensorShapeProto.Dimension: 1 dim_value, 2 dim_param.
int64_t parse_dimension(Reader r) {
  int64_t value = -1;
  while (!r.done()) {
    const uint64_t key = r.varint();
    if ((key >> 3) == 1 && (key & 7) == 0) value = static_cast<int64_t>(r.varint());
    else r.skip(key & 7);
  }
  return value > 0 ? value : -1;
}

// ValueInfoProto: 1 name, 2 TypeProto{1 tensor_type{1 elem_type, 2 shape{1 dim}}}.
OnnxTensorInfo parse_value_info(Reader r, bool& ok) {
  OnnxTensorInfo info;
  while (!r.done()) {
    const uint64_t key = r.varint();
    const uint64_t field = key >> 3;
    if (field == 1 && (key & 7) == 2) {
      info.name = r.str();
    } else if (field == 2 && (key & 7) == 2) {
      Reader type = r.bytes();
      while (!type.done()) {
        const uint64_t tkey = type.varint();
        if ((tkey >> 3) == 1 && (tkey & 7) == 2) {
          Reader tensor = type.bytes();
          while (!tensor.done()) {
            const uint64_t k = tensor.varint();
            if ((k >> 3) == 2 && (k & 7) == 2) {
              Reader shape = tensor.bytes();
              while (!shape.done()) {
                const uint64_t sk = shape.varint();
                if ((sk >> 3) == 1 && (sk & 7) == 2) info.shape.push_back(parse_dimension(shape.bytes()));
                else shape.skip(sk & 7);
              }
            } else {
              tensor.skip(k & 7);
            }
          }
        } else {
          type.skip(tkey & 7);
        }
      }
    } else {
      r.skip(key & 7);
    }
  }
  ok = ok && r.ok;
  return info;
}

// TensorProto field 8 = name (to drop initializers listed as inputs in old opsets).
std::string parse_initializer_name(Reader r) {
  while (!r.done()) {
    const uint64_t key = r.varint();
    if ((key >> 3) == 8 && (key & 7) == 2) return r.str();
    r.skip(key & 7);
  }
  return {};
}

}  // namespace

OnnxModelInfo read_onnx_model_info(const std::filesystem::path& path) {
  // Regular files only, size-limited (a folder or FIFO is one clear error, issue 22).
  const std::string data = read_regular_file(path, kMaxModelFileBytes, "model file");
  if (data.empty()) throw Error(path, "model file is empty");

  Reader model{reinterpret_cast<const uint8_t*>(data.data()), reinterpret_cast<const uint8_t*>(data.data()) + data.size()};
  OnnxModelInfo info;
  std::set<std::string> initializers;
  bool found_graph = false, ok = true;
  while (!model.done()) {
    const uint64_t key = model.varint();
    // ModelProto field 7 = graph (GraphProto): 11 input, 12 output, 5 initializer.
    if ((key >> 3) == 7 && (key & 7) == 2) {
      found_graph = true;
      Reader graph = model.bytes();
      while (!graph.done()) {
        const uint64_t gkey = graph.varint();
        const uint64_t field = gkey >> 3;
        if ((gkey & 7) == 2 && field == 11) info.inputs.push_back(parse_value_info(graph.bytes(), ok));
        else if ((gkey & 7) == 2 && field == 12) info.outputs.push_back(parse_value_info(graph.bytes(), ok));
        else if ((gkey & 7) == 2 && field == 5) initializers.insert(parse_initializer_name(graph.bytes()));
        else graph.skip(gkey & 7);
      }
      ok = ok && graph.ok;
    } else {
      model.skip(key & 7);
    }
  }
  if (!model.ok || !ok || !found_graph || info.inputs.empty() || info.outputs.empty())
    throw Error(path, "not a valid ONNX model (no graph inputs/outputs found)");
  std::erase_if(info.inputs, [&](const OnnxTensorInfo& t) { return initializers.count(t.name) > 0; });
  if (info.inputs.empty()) throw Error(path, "ONNX model has no non-initializer input");
  return info;
}

cv::dnn::Net load_onnx_net(const std::filesystem::path& model_path) {
  cv::dnn::Net net;
  try {
    net = cv::dnn::readNetFromONNX(model_path.string());
  } catch (const cv::Exception& e) {
    throw Error(model_path, std::string("OpenCV cannot load the ONNX model: ") + e.err);
  }
  if (net.empty()) throw Error(model_path, "OpenCV cannot load the ONNX model");
  net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return net;
}

}  // namespace semap

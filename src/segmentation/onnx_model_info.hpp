#pragma once
// Reads the graph inputs/outputs (names and shapes) of an ONNX file without a protobuf
// dependency: cv::dnn 4.6 does not expose the input size before a forward pass, so the
// segmenters read it here (a minimal protobuf wire-format walk over ModelProto.graph).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/dnn.hpp>

namespace semap {

struct OnnxTensorInfo {
  std::string name;
  std::vector<int64_t> shape;  ///< -1 for symbolic/unknown dimensions
};

struct OnnxModelInfo {
  std::vector<OnnxTensorInfo> inputs;   ///< graph inputs that are not initializers
  std::vector<OnnxTensorInfo> outputs;
};

/// Throws semap::Error naming the file when it is missing or not an ONNX model.
OnnxModelInfo read_onnx_model_info(const std::filesystem::path& path);

/// Loads an ONNX model into cv::dnn on the CPU backend; semap::Error naming the file when
/// OpenCV cannot load it.
cv::dnn::Net load_onnx_net(const std::filesystem::path& model_path);

}  // namespace semap

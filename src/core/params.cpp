#include "core/params.hpp"

#include "core/error.hpp"

namespace semap {

void require_param(bool ok, std::string_view key, std::string_view reason) {
  if (!ok) throw Error("config key '" + std::string(key) + "'", std::string(reason));
}

}  // namespace semap

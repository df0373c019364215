#pragma once
// The dashboard's static files (tuner/service/web/, and Debian's Chart.js), embedded in the
// binary at build time by web/embed.cmake. Private to tuner/service.
#include <cstddef>
#include <span>

namespace ftc::tune::service_detail {

struct WebAsset {
  const char* path;  // the URL path it is served at
  const char* type;  // its media type (text: UTF-8)
  const unsigned char* data;
  std::size_t size;
};

std::span<const WebAsset> web_assets();

}  // namespace ftc::tune::service_detail

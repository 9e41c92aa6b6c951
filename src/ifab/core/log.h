#pragma once
/// \file Logging through spdlog. Library code logs; only the app decides the level and sink.

#include <spdlog/spdlog.h>

namespace ifab {

/// Set the global log level from a name (trace, debug, info, warn, error, off).
inline void SetLogLevel(const std::string& level) {
  spdlog::set_level(spdlog::level::from_str(level));
}

}  // namespace ifab

#pragma once
// What every application route shares: the database connections, the metrics and the limits.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "app/connection_pool.hpp"
#include "pintag/server/metrics.hpp"

namespace pintag::app {

inline constexpr std::string_view kDetectionsCounter = "pintag_detections_total";
inline constexpr std::string_view kUnknownKeysCounter = "pintag_detections_unknown_key_total";
inline constexpr std::string_view kScansCounter = "pintag_scans_total";

struct AppContext {
  std::shared_ptr<ConnectionPool> pool;
  std::shared_ptr<ConnectionPool>
      scan_log;  ///< where scans are logged: pool's file, or a replica's own
  std::shared_ptr<server::Metrics> metrics;
  std::int64_t max_pixels = 40'000'000;  ///< decoded pixels per uploaded photo
};

}  // namespace pintag::app

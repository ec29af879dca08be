#pragma once
// What every application route shares: the database connections, the metrics and the limits.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "app/connection_pool.hpp"
#include "app/pixel_budget.hpp"
#include "app/scan_log_writer.hpp"
#include "app/write_gate.hpp"
#include "pintag/server/metrics.hpp"
#include "replica/follow_status.hpp"
#include "replica/snapshot_publisher.hpp"

namespace pintag::app {

inline constexpr std::string_view kLabelsRenderedCounter = "pintag_labels_rendered_total";
inline constexpr std::string_view kTagsRenderedCounter = "pintag_tags_rendered_total";
inline constexpr std::string_view kScansCounter = "pintag_scans_total";
inline constexpr std::string_view kScanLogFailuresCounter = "pintag_scan_log_failures_total";
inline constexpr std::string_view kDetectionsCounter = "pintag_detections_total";
inline constexpr std::string_view kUnknownKeysCounter = "pintag_detections_unknown_key_total";
inline constexpr std::string_view kPixelBudgetWaitsCounter = "pintag_pixel_budget_waits_total";

struct AppContext {
  std::shared_ptr<ConnectionPool> pool;
  /// Writes scans to the pool's file, or a replica's own (docs/SCALING.md), off the worker
  /// threads.
  std::shared_ptr<ScanLogWriter> scan_log;
  std::shared_ptr<server::Metrics> metrics;  ///< the counters above are defined in it
  std::int64_t max_pixels = 40'000'000;      ///< decoded pixels per uploaded photo
  std::size_t max_batch = 100;               ///< labels per POST /api/v1/labels; more is 413
  int max_tag_px = 4096;                     ///< largest ?px= of a tag image (square side)
  /// Pixels of photos being decoded and detected and of PNGs being rendered, at once over every
  /// request (--max-pixels-in-flight).
  std::shared_ptr<PixelBudget> pixel_budget;
  /// Requests that write the database at once (the route table's Writing<> rows).
  std::shared_ptr<WriteGate> write_gate;
  /// Replication (docs/SCALING.md): which this server is, its primary when a replica, and the
  /// snapshot it hands replicas when a primary started with --snapshot (else none).
  bool read_only = false;
  std::string primary_url;
  std::shared_ptr<replica::SnapshotPublisher> publisher;
  std::shared_ptr<const replica::FollowStatus> follow_status;  ///< AppConfig::follow_status
};

/// Room for an image of `pixels` under the context's budget (--max-pixels-in-flight), held until
/// the reservation ends; a call that had to wait is counted in kPixelBudgetWaitsCounter.
inline PixelBudget::Reservation HoldPixels(const AppContext& context, std::int64_t pixels) {
  bool waited = false;
  PixelBudget::Reservation held = context.pixel_budget->reserve(pixels, &waited);
  if (waited) context.metrics->increment(kPixelBudgetWaitsCounter);
  return held;
}

}  // namespace pintag::app

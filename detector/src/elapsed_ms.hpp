#pragma once
// Stage timings (DetectResult::timings): milliseconds between two steady-clock readings, shared by
// the pipeline and the readers so that every stage is timed the same way.

#include <chrono>

namespace pintag {

inline double ElapsedMs(std::chrono::steady_clock::time_point from,
                        std::chrono::steady_clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

}  // namespace pintag

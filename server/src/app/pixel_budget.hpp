#pragma once
// A bound on the image pixels the server holds at once: photos being decoded and detected, label
// and tag PNGs being rendered. An upload holds its pixels (the size its header claims) from just
// before decoding until its answer is built, a PNG from just before rendering until it is
// encoded; what does not fit waits its turn. Each costs about 7 to 8 bytes a pixel at peak (a
// 33 MP photo: 230 MB more resident memory; a 1200 dpi label PNG, 33.5 MP: 232 MB), so without
// this bound --threads requests of the largest size each could take more memory than the
// machine has.

#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace pintag::app {

class PixelBudget {
 public:
  /// `capacity` pixels may be held at once; it must be positive.
  explicit PixelBudget(std::int64_t capacity);

  /// Pixels held until it ends (moved-from: none).
  class Reservation {
   public:
    Reservation() = default;
    Reservation(Reservation&& other) noexcept;
    Reservation& operator=(Reservation&& other) noexcept;
    Reservation(const Reservation&) = delete;
    Reservation& operator=(const Reservation&) = delete;
    ~Reservation();
    std::int64_t pixels() const { return pixels_; }

   private:
    friend class PixelBudget;
    Reservation(PixelBudget* budget, std::int64_t pixels) : budget_(budget), pixels_(pixels) {}
    PixelBudget* budget_ = nullptr;
    std::int64_t pixels_ = 0;
  };

  /// Waits until the pixels fit beside those held, in the order callers arrived (a large photo
  /// is not overtaken for ever by small ones), then holds them. A request larger than the whole
  /// capacity waits until nothing else is held and then runs alone. `waited`, when given, is set
  /// to whether the call had to wait.
  Reservation reserve(std::int64_t pixels, bool* waited = nullptr);

  /// Pixels held now, and the most held at once since the budget was made.
  std::int64_t held() const;
  std::int64_t peak() const;
  /// Callers waiting in reserve() now.
  std::int64_t waiting() const;

 private:
  void release(std::int64_t pixels);

  const std::int64_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable turn_;
  std::int64_t held_ = 0;
  std::int64_t peak_ = 0;
  std::uint64_t next_ticket_ = 0;  // the ticket the next caller takes
  std::uint64_t serving_ = 0;      // the ticket whose turn it is
};

}  // namespace pintag::app

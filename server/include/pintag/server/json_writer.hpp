#pragma once
// Writes JSON text straight into a string, for answers on hot routes (a pincode lookup is 5-6 KB
// of offices). Building an nlohmann::json tree first cost a third of a lookup's time in malloc
// and free. Keys come out in the order they are written. Text is escaped per RFC 8259; a byte
// sequence that is not UTF-8 is written as U+FFFD, so the output is always valid JSON.

#include <concepts>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pintag::server {

class JsonWriter {
 public:
  JsonWriter& beginObject() { return open('{'); }
  JsonWriter& endObject() { return close('}'); }
  JsonWriter& beginArray() { return open('['); }
  JsonWriter& endArray() { return close(']'); }
  /// The next member's name; the value written next belongs to it.
  JsonWriter& key(std::string_view name);

  JsonWriter& value(std::string_view text);
  JsonWriter& value(const char* text) { return value(std::string_view(text)); }
  JsonWriter& value(const std::string& text) { return value(std::string_view(text)); }
  /// Any integer type (bool has its own overload); unsigned values past INT64_MAX are not
  /// representable and must not be passed.
  template <std::integral T>
  requires(!std::same_as<T, bool>) JsonWriter& value(T number) {
    return integer(static_cast<std::int64_t>(number));
  }
  /// Shortest text that reads back as the same double, always with a fraction or exponent (28.0,
  /// not 28), so a client reads a float back; NaN and infinities as null.
  JsonWriter& value(double number);
  JsonWriter& value(bool flag);
  JsonWriter& null();
  template <typename T>
  JsonWriter& value(const std::optional<T>& maybe) {
    return maybe ? value(*maybe) : null();
  }

  /// The text written so far; the writer is empty afterwards.
  std::string take();

 private:
  JsonWriter& open(char bracket);
  JsonWriter& close(char bracket);
  JsonWriter& integer(std::int64_t number);
  void beforeValue();
  void writeString(std::string_view text);

  std::string out_;
  // One entry per open object or array: true until its first element is written.
  std::vector<bool> first_;
  bool after_key_ = false;
};

}  // namespace pintag::server

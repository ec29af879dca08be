#include "pintag/db/sort_plan.hpp"

#include <algorithm>
#include <map>
#include <set>

#include "guard.hpp"
#include "pintag/codec/utf8.hpp"
#include "pintag/db/csv.hpp"
#include "pintag/db/text.hpp"
#include "sha256.hpp"
#include "sort_plan_internal.hpp"

namespace pintag::db {
namespace {

using detail::Guard;

bool IsPrefix(std::string_view prefix) {
  return !prefix.empty() && prefix.size() <= 6 &&
         std::all_of(prefix.begin(), prefix.end(), [](char c) { return c >= '0' && c <= '9'; });
}

Error TooManyRules(std::string_view at) {
  return {ErrorCode::kTooLarge,
          std::string(at) + "a sort plan has at most " + std::to_string(kMaxPlanRules) + " rules"};
}

/// A bin is shown on screens and in the plan's CSV, which is opened in spreadsheets: a bin
/// starting with = + - or @ would be run there as a formula. Refused rather than escaped, since the
/// CSV is put back as it reads (an escaping ' would become part of the bin).
std::optional<Error> CheckBin(std::string_view field, std::string_view bin) {
  if (auto error = CheckShownName(field, bin, kMaxBinBytes)) return error;
  if (!bin.empty() && std::string_view("=+-@").find(bin.front()) != std::string_view::npos) {
    return Error{ErrorCode::kInvalid,
                 std::string(field) + " '" + std::string(bin.substr(0, 64)) + "' starts with '" +
                     bin.front() +
                     "', which a spreadsheet opening the plan's CSV runs as a formula"};
  }
  return std::nullopt;
}

/// `error` with `at` ("line 4: ") put before its message.
Error At(std::string_view at, Error error) {
  error.message.insert(0, at);
  return error;
}

/// A stored plan's name that reads like `name` but is written with other code points, if any.
std::optional<std::string> LookalikePlanName(Connection& connection, std::string_view name) {
  const std::string canonical = CanonicalForm(name);
  Statement names = connection.prepare("SELECT name FROM sort_plans");
  while (names.step()) {
    std::string stored = names.getText(0);
    if (stored != name && CanonicalForm(stored) == canonical) return stored;
  }
  return std::nullopt;
}

/// `text` quoted, with its code points beyond ASCII after it ("'café' (U+00E9)"): two names that
/// read alike print alike, and these say how they differ.
std::string QuotedWithCodePoints(std::string_view text) {
  std::string quoted = QuotedPrefix(text, 100);
  std::string code_points;
  for (std::size_t i = 0; i < text.size() && i < 100;) {
    const Utf8CodePoint point = DecodeUtf8(text, i);
    if (point.length == 0) break;
    if (point.value >= 0x80) {
      if (!code_points.empty()) code_points += ' ';
      code_points += CodePointName(point.value);
    }
    i += point.length;
  }
  if (!code_points.empty()) quoted += " (" + code_points + ")";
  return quoted;
}

/// How two strings that read alike differ, for a message.
constexpr std::string_view kOtherCodePoints =
    "written with other Unicode code points (a letter and its accent as one character or as two, "
    "say)";

/// Why `name` is not the stored `lookalike` though it reads the same.
std::string ReadsLike(std::string_view name, std::string_view lookalike) {
  return "the plan " + QuotedWithCodePoints(lookalike) + " reads the same as " +
         QuotedWithCodePoints(name) + " but is " + std::string(kOtherCodePoints);
}

/// `error` about the plan called `name`, with the stored plan that reads like it named, if any.
Error NamingALookalike(Connection& connection, std::string_view name, Error error,
                       std::string_view then) {
  if (const auto lookalike = LookalikePlanName(connection, name)) {
    error.message += ": " + ReadsLike(name, *lookalike) + "; " + std::string(then);
  }
  return error;
}

constexpr std::string_view kAskByStoredName =
    "ask for it by its name as stored (GET /api/v1/sortplans lists them)";

Error UnknownPlan(Connection& connection, std::string_view name) {
  // A name asked for may be long (a URL's path).
  return NamingALookalike(connection, name,
                          {ErrorCode::kNotFound, "no sort plan named " + QuotedPrefix(name, 100)},
                          kAskByStoredName);
}

bool ByPrefix(const SortRule& a, const SortRule& b) {
  return a.prefix < b.prefix;
}

/// Writes the plan in the caller's transaction and returns it as stored (rules by prefix, the
/// description it kept). `replaced`: set to whether a plan of that name was there.
SortPlan WritePlan(Connection& connection, const SortPlan& plan, bool* replaced = nullptr,
                   StoredDescription description = StoredDescription::kReplace) {
  SortPlan stored = plan;
  if (description == StoredDescription::kKeep) {
    Statement kept = connection.prepare("SELECT description FROM sort_plans WHERE name = ?1");
    kept.bind(1, plan.name);
    if (kept.step()) stored.description = kept.getText(0);
  }
  const bool deleted =
      connection.prepare("DELETE FROM sort_plans WHERE name = ?1").bind(1, plan.name).run() > 0;
  if (replaced != nullptr) *replaced = deleted;
  connection
      .prepare(std::string("INSERT INTO sort_plans (name, fallback_bin, description, updated_at) "
                           "VALUES (?1, ?2, ?3, ") +
               detail::kNowSql + ")")
      .bind(1, stored.name)
      .bind(2, stored.fallback_bin)
      .bind(3, stored.description)
      .run();
  const std::int64_t id = connection.lastInsertRowid();
  Statement insert =
      connection.prepare("INSERT INTO sort_rules (plan_id, prefix, bin) VALUES (?1, ?2, ?3)");
  for (const SortRule& rule : stored.rules) {
    insert.bind(1, id).bind(2, rule.prefix).bind(3, rule.bin).run();
    insert.reset();
  }
  std::sort(stored.rules.begin(), stored.rules.end(), ByPrefix);
  return stored;
}

/// Whether a plan called `name` is stored (its rules unread).
bool HasPlanNamed(Connection& connection, std::string_view name) {
  return connection.prepare("SELECT 1 FROM sort_plans WHERE name = ?1").bind(1, name).step();
}

/// The stored plan called `name`, if there is one.
std::optional<SortPlan> ReadPlan(Connection& connection, std::string_view name) {
  Statement head = connection.prepare(
      "SELECT id, name, fallback_bin, description FROM sort_plans WHERE name = ?1");
  head.bind(1, name);
  if (!head.step()) return std::nullopt;
  SortPlan plan{head.getText(1), head.getText(2), head.getText(3), {}};
  Statement rules =
      connection.prepare("SELECT prefix, bin FROM sort_rules WHERE plan_id = ?1 ORDER BY prefix");
  rules.bind(1, head.getInt64(0));
  while (rules.step()) plan.rules.push_back({rules.getText(0), rules.getText(1)});
  return plan;
}

/// Each field behind its length, so no two different plans hash the same bytes.
void AppendField(std::string& out, std::string_view field) {
  out += std::to_string(field.size());
  out += ':';
  out += field;
}

/// Why the plan stored under `name` (none when empty) fails `condition`, or nothing when it
/// meets it. `doing` ends the message for a plan that must exist ("to replace").
std::optional<Error> UnmetCondition(std::string_view name, const std::optional<SortPlan>& stored,
                                    const PlanCondition& condition, std::string_view doing) {
  const std::string quoted = QuotedPrefix(name, 100);
  const std::string version = stored ? PlanVersion(*stored) : std::string();
  if (condition.match && !stored) {
    return Error{ErrorCode::kPrecondition,
                 "there is no sort plan named " + quoted + " " + std::string(doing)};
  }
  if (condition.match && !condition.match->contains(version)) {
    return Error{ErrorCode::kPrecondition, "sort plan " + quoted +
                                               " is not at the version given (it is now \"" +
                                               version + "\"): read it again and redo the change"};
  }
  if (condition.none_match && stored && condition.none_match->contains(version)) {
    return Error{ErrorCode::kPrecondition,
                 condition.none_match->any
                     ? "sort plan " + quoted + " exists, and If-None-Match: * asks that none does"
                     : "sort plan " + quoted + " is at a version If-None-Match excludes"};
  }
  return std::nullopt;
}

/// Two of the plan's bins that read alike but differ in code points: a sorter would take them for
/// two bins while every screen and label shows one.
std::optional<Error> BinsThatReadAlike(const SortPlan& plan) {
  const auto where = [](const SortRule* rule) {
    return rule == nullptr ? std::string("fallback bin") : "bin for prefix " + rule->prefix;
  };
  // Each distinct bin normalised once (a plan of 100,000 rules has a few dozen bins): by its
  // bytes, then by its canonical form, with the rule it first came in (nullptr: the fallback).
  std::map<std::string_view, const SortRule*> bins;
  std::map<std::string, std::pair<std::string_view, const SortRule*>> canonical_bins;
  const auto check = [&](std::string_view bin, const SortRule* rule) -> std::optional<Error> {
    if (!bins.try_emplace(bin, rule).second) return std::nullopt;
    const auto [first, inserted] = canonical_bins.try_emplace(CanonicalForm(bin), bin, rule);
    if (inserted) return std::nullopt;
    return Error{ErrorCode::kInvalid,
                 "the " + where(rule) + " " + QuotedWithCodePoints(bin) + " and the " +
                     where(first->second.second) + " " + QuotedWithCodePoints(first->second.first) +
                     " read the same but are " + std::string(kOtherCodePoints) +
                     ": a sorter would take them for two bins; write them alike"};
  };
  if (auto error = check(plan.fallback_bin, nullptr)) return error;
  for (const SortRule& rule : plan.rules) {
    if (auto error = check(rule.bin, &rule)) return error;
  }
  return std::nullopt;
}

}  // namespace

std::optional<Error> CheckRule(const SortRule& rule) {
  if (!IsPrefix(rule.prefix)) {
    return Error{ErrorCode::kInvalid,
                 "rule prefix " + QuotedPrefix(rule.prefix, 40) + " is not 1 to 6 digits"};
  }
  if (rule.prefix[0] == '0') {
    return Error{ErrorCode::kInvalid, "rule prefix '" + rule.prefix +
                                          "' starts with 0, as no pincode does: the rule could "
                                          "never match"};
  }
  return CheckBin("bin for prefix " + rule.prefix, rule.bin);
}

std::optional<Error> CheckPlan(const SortPlan& plan) {
  if (auto error = CheckShownName("plan name", plan.name, kMaxBinBytes)) return error;
  // A name is a path segment (/api/v1/sortplans/{name}, ?plan=): "." and ".." would be read as
  // steps of the path by every client, and these characters must be percent-encoded in a URL
  // (in a query, `+` reads as a space and `&` and `=` split it: ?plan=a+b asked for "a b").
  if (plan.name == "." || plan.name == ".." ||
      plan.name.find_first_of("/?#%\\+&=") != std::string::npos) {
    return Error{ErrorCode::kInvalid, "plan name '" + plan.name.substr(0, 64) +
                                          "' is '.' or '..' or holds one of / ? # % \\ + & =, "
                                          "which a URL would have to encode"};
  }
  if (auto error = CheckBin("fallback bin", plan.fallback_bin)) return error;
  if (auto error = CheckText("description", plan.description, kMaxLabelBytes, true)) return error;
  if (plan.rules.size() > kMaxPlanRules) {
    return Error{ErrorCode::kTooLarge, "the plan has " + std::to_string(plan.rules.size()) +
                                           " rules; a sort plan has at most " +
                                           std::to_string(kMaxPlanRules)};
  }
  std::set<std::string_view> prefixes;
  for (const SortRule& rule : plan.rules) {
    if (auto error = CheckRule(rule)) return error;
    if (!prefixes.insert(rule.prefix).second) {
      return Error{ErrorCode::kInvalid, "prefix " + rule.prefix + " appears twice"};
    }
  }
  return BinsThatReadAlike(plan);
}

Routing RouteWith(const SortPlan& plan, Pincode pincode) {
  const std::string digits = pincode.str();
  const SortRule* best = nullptr;
  for (const SortRule& rule : plan.rules) {
    if (digits.starts_with(rule.prefix) && (!best || rule.prefix.size() > best->prefix.size())) {
      best = &rule;
    }
  }
  if (!best) return {plan.fallback_bin, std::nullopt};
  return {best->bin, *best};
}

Result<SortPlan> ParsePlanCsv(std::string_view name, std::string_view csv) {
  SortPlan plan;
  plan.name = std::string(name);
  CsvReader reader(csv);
  std::string error;
  const auto header = reader.next(&error);
  // Spaces around a field are dropped ("11, delhi", as people write CSV by hand): no prefix or
  // bin may hold them at an end (CheckShownName).
  const auto field = [](const auto& record, std::size_t i) {
    return std::string(TrimSpaces(record->fields[i]));
  };
  if (!header || !error.empty() || header->fields.size() != 2 || field(header, 0) != "prefix" ||
      field(header, 1) != "bin") {
    return Error{ErrorCode::kInvalid, "line 1: expected the header 'prefix,bin'"};
  }
  bool have_fallback = false;
  std::map<std::string, std::int64_t> line_of;  // each rule's prefix, and its line
  while (const auto record = reader.next(&error)) {
    const std::string at = "line " + std::to_string(record->line) + ": ";
    if (!error.empty()) return Error{ErrorCode::kInvalid, at + error};
    if (record->fields.size() != 2) {
      return Error{ErrorCode::kInvalid,
                   at + "expected 2 fields, got " + std::to_string(record->fields.size())};
    }
    if (field(record, 0) == "*") {
      if (have_fallback) return Error{ErrorCode::kInvalid, at + "a second fallback row '*'"};
      have_fallback = true;
      plan.fallback_bin = field(record, 1);
      if (auto problem = CheckBin("fallback bin", plan.fallback_bin)) {
        return At(at, *problem);
      }
      continue;
    }
    // Stopped at the first rule too many: the rest is not read into memory.
    if (plan.rules.size() == kMaxPlanRules) return TooManyRules(at);
    SortRule rule{field(record, 0), field(record, 1)};
    if (auto problem = CheckRule(rule)) return At(at, *problem);
    const auto [first, inserted] = line_of.try_emplace(rule.prefix, record->line);
    if (!inserted) {
      return Error{ErrorCode::kInvalid, at + "prefix " + rule.prefix +
                                            " appears twice (first on line " +
                                            std::to_string(first->second) + ")"};
    }
    plan.rules.push_back(std::move(rule));
  }
  if (!have_fallback) {
    return Error{ErrorCode::kInvalid, "no fallback row: add '*,<bin>' for unmatched pincodes"};
  }
  if (auto problem = CheckPlan(plan)) return *problem;
  std::sort(plan.rules.begin(), plan.rules.end(),
            [](const SortRule& a, const SortRule& b) { return a.prefix < b.prefix; });
  return plan;
}

std::string PlanToCsv(const SortPlan& plan) {
  std::string out = "prefix,bin\n*," + CsvField(plan.fallback_bin) + "\n";
  std::vector<SortRule> rules = plan.rules;
  std::sort(rules.begin(), rules.end(),
            [](const SortRule& a, const SortRule& b) { return a.prefix < b.prefix; });
  for (const SortRule& rule : rules) out += rule.prefix + "," + CsvField(rule.bin) + "\n";
  return out;
}

Result<bool> SavePlan(Connection& connection, const SortPlan& plan, StoredDescription description) {
  auto saved = SavePlanIf(connection, plan, {}, description);
  if (!saved) return saved.error();
  return saved->replaced;
}

std::string PlanVersion(const SortPlan& plan) {
  std::vector<SortRule> rules = plan.rules;
  std::sort(rules.begin(), rules.end(), ByPrefix);
  std::string bytes;
  AppendField(bytes, plan.name);
  AppendField(bytes, plan.fallback_bin);
  AppendField(bytes, plan.description);
  for (const SortRule& rule : rules) {
    AppendField(bytes, rule.prefix);
    AppendField(bytes, rule.bin);
  }
  const std::string digest = detail::Sha256({bytes});
  static constexpr char kHex[] = "0123456789abcdef";
  std::string version;
  for (std::size_t i = 0; i < 16; ++i) {
    const auto byte = static_cast<unsigned char>(digest[i]);
    version += kHex[byte >> 4];
    version += kHex[byte & 15];
  }
  return version;
}

bool PlanVersions::contains(std::string_view version) const {
  return any || std::find(versions.begin(), versions.end(), version) != versions.end();
}

Result<SavedPlan> SavePlanIf(Connection& connection, const SortPlan& plan,
                             const PlanCondition& condition, StoredDescription description) {
  if (auto error = CheckPlan(plan)) return *error;
  return Guard([&]() -> Result<SavedPlan> {
    Transaction transaction(connection);
    if (condition.match || condition.none_match) {
      // Read under the write lock: no other writer can change the plan between here and commit.
      const std::optional<SortPlan> stored = ReadPlan(connection, plan.name);
      if (auto unmet = UnmetCondition(plan.name, stored, condition, "to replace")) {
        return stored ? *unmet : NamingALookalike(connection, plan.name, *unmet, kAskByStoredName);
      }
    }
    if (!HasPlanNamed(connection, plan.name)) {
      if (const auto lookalike = LookalikePlanName(connection, plan.name)) {
        return Error{ErrorCode::kConflict,
                     "sort plan " + QuotedWithCodePoints(plan.name) +
                         " would be a second plan: " + ReadsLike(plan.name, *lookalike) +
                         "; name it as stored to change it, or choose a name that reads "
                         "differently"};
      }
    }
    SavedPlan saved;
    saved.plan = WritePlan(connection, plan, &saved.replaced, description);
    transaction.commit();
    saved.version = PlanVersion(saved.plan);
    return saved;
  });
}

Result<SortPlan> GetPlan(Connection& connection, std::string_view name) {
  return Guard([&]() -> Result<SortPlan> {
    std::optional<SortPlan> plan = ReadPlan(connection, name);
    if (!plan) return UnknownPlan(connection, name);
    return std::move(*plan);
  });
}

Result<bool> HasPlan(Connection& connection, std::string_view name) {
  return Guard([&]() -> Result<bool> { return HasPlanNamed(connection, name); });
}

Result<std::vector<std::string>> ListPlans(Connection& connection) {
  return Guard([&]() -> Result<std::vector<std::string>> {
    Statement s = connection.prepare("SELECT name FROM sort_plans ORDER BY name");
    std::vector<std::string> names;
    while (s.step()) names.push_back(s.getText(0));
    return names;
  });
}

Result<SortPlan> DeletePlan(Connection& connection, std::string_view name,
                            const PlanCondition& condition) {
  if (name == kDefaultPlanName) {
    return Error{ErrorCode::kConflict,
                 "the default sort plan cannot be deleted: labels and scans that name no plan "
                 "use it; replace its rules instead"};
  }
  return Guard([&]() -> Result<SortPlan> {
    Transaction transaction(connection);
    // Read under the write lock, as a save reads it: what is returned is what was deleted.
    std::optional<SortPlan> stored = ReadPlan(connection, name);
    if (auto unmet = UnmetCondition(name, stored, condition, "to delete")) {
      return stored ? *unmet : NamingALookalike(connection, name, *unmet, kAskByStoredName);
    }
    if (!stored) return UnknownPlan(connection, name);
    connection.prepare("DELETE FROM sort_plans WHERE name = ?1").bind(1, name).run();
    transaction.commit();
    return std::move(*stored);
  });
}

Result<Routing> Route(Connection& connection, Pincode pincode, std::string_view plan) {
  return Guard([&]() -> Result<Routing> {
    Statement head = connection.prepare("SELECT id, fallback_bin FROM sort_plans WHERE name = ?1");
    head.bind(1, plan);
    if (!head.step()) return UnknownPlan(connection, plan);
    // The six prefixes of the pincode; the primary key (plan_id, prefix) finds each directly.
    const std::string digits = pincode.str();
    Statement rule = connection.prepare(
        "SELECT prefix, bin FROM sort_rules WHERE plan_id = ?1 AND prefix IN (?2, ?3, ?4, ?5, "
        "?6, ?7) ORDER BY length(prefix) DESC LIMIT 1");
    rule.bind(1, head.getInt64(0));
    for (int length = 1; length <= 6; ++length) {
      rule.bind(1 + length, std::string_view(digits).substr(0, length));
    }
    if (!rule.step()) return Routing{head.getText(1), std::nullopt};
    SortRule matched{rule.getText(0), rule.getText(1)};
    return Routing{matched.bin, matched};
  });
}

namespace detail {

void InsertDefaultPlan(Connection& connection) {
  SortPlan plan{std::string(kDefaultPlanName),
                "manual",
                "one bin per first two digits of the pincode (shipped with the seed)",
                {}};
  Statement s = connection.prepare(
      "SELECT DISTINCT substr(CAST(pincode AS TEXT), 1, 2) FROM pincodes ORDER BY 1");
  while (s.step()) plan.rules.push_back({s.getText(0), s.getText(0)});
  WritePlan(connection, plan);
}

}  // namespace detail
}  // namespace pintag::db

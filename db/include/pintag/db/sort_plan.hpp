#pragma once
// Sort plans: which bin of a sorting facility each pincode goes to. A plan is a set of rules
// `prefix (1–6 digits) → bin` and a fallback bin; the longest matching prefix wins, and a pincode
// no rule matches goes to the fallback (explicitly: the result says no rule matched).
//
// The seed ships the plan "default": one bin per first two digits of the pincode (bins "11" …
// "85", fallback "manual"), because two digits are the postal circle's sub-region and the rules
// say exactly that, while postal circles do not follow prefix boundaries (24x and 26x are split
// between Uttar Pradesh and Uttarakhand, 81x–82x between Bihar and Jharkhand).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pintag/codec/pincode.hpp"
#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

inline constexpr std::string_view kDefaultPlanName = "default";

struct SortRule {
  std::string prefix;  ///< 1–6 ASCII digits, the first 1–9
  std::string bin;     ///< 1–64 bytes of text
  bool operator==(const SortRule&) const = default;
};

struct SortPlan {
  std::string name;             ///< 1–64 bytes of text, unique
  std::string fallback_bin;     ///< where pincodes no rule matches go
  std::string description;      ///< free text, may be empty
  std::vector<SortRule> rules;  ///< ascending by prefix when read back; prefixes unique
  bool operator==(const SortPlan&) const = default;
};

struct Routing {
  std::string bin;
  std::optional<SortRule> rule;  ///< the rule that matched; nothing when the fallback was used
};

/// Rules a plan may have. A plan with a rule for every pincode has about 19,000; past the limit
/// a PUT is refused (kTooLarge) before it costs seconds and hundreds of megabytes.
inline constexpr std::size_t kMaxPlanRules = 100'000;

/// Nothing when the rule is well formed, else kInvalid saying what is wrong: a prefix is 1–6
/// digits and does not start with 0 (no pincode does, so such a rule could never match); the
/// bin is 1–64 bytes of text.
std::optional<Error> CheckRule(const SortRule& rule);

/// Nothing when the plan is well formed, else kInvalid saying what is wrong (or kTooLarge for
/// more than kMaxPlanRules rules).
std::optional<Error> CheckPlan(const SortPlan& plan);

/// Routes with a plan already in memory (no database); longest prefix wins.
Routing RouteWith(const SortPlan& plan, Pincode pincode);

/// Plan CSV: a `prefix,bin` header, then one rule per row; the row with prefix `*` gives the
/// fallback bin and must appear exactly once. RFC 4180 quoting. Errors name the line; more than
/// kMaxPlanRules rules: kTooLarge, read no further.
Result<SortPlan> ParsePlanCsv(std::string_view name, std::string_view csv);
/// The inverse: header, `*` row, then rules in ascending prefix order.
std::string PlanToCsv(const SortPlan& plan);

/// What saving over a stored plan does with its description.
enum class StoredDescription {
  kReplace,  ///< the saved plan's description replaces it
  kKeep,     ///< it stays (a plan from CSV, which has no place for one); a new plan gets the given
};

/// Creates the plan, or replaces the one with the same name (rules and all), in one transaction;
/// true when it replaced one (decided inside the transaction, so of two writers only one creates).
Result<bool> SavePlan(Connection& connection, const SortPlan& plan,
                      StoredDescription description = StoredDescription::kReplace);

/// The version of a plan as stored: 32 hex digits of SHA-256 over its name, fallback bin,
/// description and rules (in prefix order), so it changes whenever any of them does, and equal
/// plans have equal versions on every server. The HTTP routes send it as the plan's ETag.
std::string PlanVersion(const SortPlan& plan);

/// A set of plan versions a write is conditional on; `any` stands for every version (HTTP's `*`).
struct PlanVersions {
  bool any = false;
  std::vector<std::string> versions;
  bool contains(std::string_view version) const;
};

/// What a conditional write requires of the stored plan (HTTP If-Match / If-None-Match).
struct PlanCondition {
  std::optional<PlanVersions> match;       ///< a stored plan whose version is in the set
  std::optional<PlanVersions> none_match;  ///< no stored plan, or one whose version is not in it
};

/// What a save left stored.
struct SavedPlan {
  bool replaced = false;  ///< a plan of that name was there before
  SortPlan plan;          ///< as stored: rules by prefix, the description it kept
  std::string version;    ///< PlanVersion(plan)
};

/// SavePlan, when the stored plan meets `condition`: the check and the write are one
/// transaction (BEGIN IMMEDIATE), so of two writers holding the same version only the first
/// succeeds. kPrecondition, and nothing written, when the condition does not hold.
Result<SavedPlan> SavePlanIf(Connection& connection, const SortPlan& plan,
                             const PlanCondition& condition,
                             StoredDescription description = StoredDescription::kReplace);
/// kNotFound for an unknown plan.
Result<SortPlan> GetPlan(Connection& connection, std::string_view name);
/// Whether a plan called `name` is stored (its rules are not read).
Result<bool> HasPlan(Connection& connection, std::string_view name);
Result<std::vector<std::string>> ListPlans(Connection& connection);  ///< names, ascending
/// Deletes the plan and its rules when the stored plan meets `condition` (checked in the same
/// transaction, as SavePlanIf checks it), and returns it as it was. kNotFound for an unknown plan;
/// kConflict for the default plan, which labels and scans naming no plan use (replace it
/// instead); kPrecondition, and nothing deleted, when the condition does not hold.
Result<SortPlan> DeletePlan(Connection& connection, std::string_view name,
                            const PlanCondition& condition = {});

/// The bin for `pincode` under the named plan, and the rule that matched; kNotFound for an
/// unknown plan. The pincode need not be in the registry (routing is by prefix only).
Result<Routing> Route(Connection& connection, Pincode pincode, std::string_view plan);

}  // namespace pintag::db

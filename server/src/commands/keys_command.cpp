// `pintag keys export` and `pintag keys lookup`: the pincode ↔ key table.

#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands/commands.hpp"
#include "commands/open_db.hpp"
#include "commands/option_checks.hpp"
#include "commands/standard_output.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/registry.hpp"

namespace pintag::cli {
namespace {

struct KeysArgs {
  std::string db = "pintag.db";
  std::string pincode;
  std::optional<int> key;
};

void Export(const KeysArgs& args) {
  db::Connection connection = OpenForReading(args.db);
  auto rows = db::ListKeys(connection);
  if (!rows) throw std::runtime_error(rows.error().message);
  std::string out = "pincode,key,status\n";
  for (const db::KeyRow& row : *rows) {
    out += row.pincode.str() + "," + std::to_string(row.key.value()) + "," +
           db::ToString(row.status) + "\n";
  }
  std::cout << out << std::flush;
  // A reader that stopped early (`| head -1`) is left to main, which exits as SIGPIPE would.
  if (!std::cout && !StandardOutputReaderHasGone()) {
    throw std::runtime_error("cannot write the key table to standard output");
  }
}

void Lookup(const KeysArgs& args) {
  if (args.pincode.empty() && !args.key) throw UsageError("give a pincode or --key KEY");
  if (!args.pincode.empty() && args.key) throw UsageError("give a pincode or --key, not both");
  // Read before the database is opened: a mistyped pincode must not create and seed one.
  std::optional<Pincode> pincode;
  if (!args.pincode.empty()) {
    const ParsedPincode parsed = ParsePincode(args.pincode);
    if (!parsed) throw UsageError("'" + args.pincode + "': " + parsed.error);
    pincode = *parsed.pincode;
  }
  db::Connection connection = OpenForReading(args.db);
  const db::Result<db::PincodeRecord> record =
      pincode ? db::LookupPincode(connection, *pincode)
              : db::LookupKey(connection, TagKey(static_cast<std::uint16_t>(*args.key)));
  if (!record) throw std::runtime_error(record.error().message);
  const db::PincodeRecord& r = record.value();
  std::cout << "pincode  " << r.pincode.str() << "\nkey      " << r.key.value() << "\nstatus   "
            << db::ToString(r.status) << "\ndistrict " << r.district << "\nstate    " << r.state
            << "\ncircle   " << r.circle << "\nregion   " << r.region << "\ndivision " << r.division
            << "\noffices  " << r.offices.size() << "\n";
  for (const db::PostOffice& office : r.offices) {
    std::cout << "  " << office.name;
    if (office.branch_type) std::cout << " (" << *office.branch_type << ")";
    if (office.district != r.district) std::cout << ", " << office.district;
    std::cout << "\n";
  }
}

void AddKeysCommand(CLI::App& app) {
  auto args = std::make_shared<KeysArgs>();
  CLI::App* keys = app.add_subcommand("keys", "The pincode-key table");
  keys->require_subcommand(1);

  CLI::App* export_cmd =
      keys->add_subcommand("export", "Print the key table as CSV: pincode,key,status");
  export_cmd->add_option("--db", args->db, "database file (created and seeded when missing)")
      ->check(DatabaseFileName())
      ->capture_default_str();
  export_cmd->callback([args] { Export(*args); });

  CLI::App* lookup =
      keys->add_subcommand("lookup", "Show a pincode's key and offices, or a key's pincode");
  lookup->add_option("pincode", args->pincode, "six-digit pincode");
  lookup->add_option("--key", args->key, "tag key, 0-32767")->transform(TagKeyText());
  lookup->add_option("--db", args->db, "database file (created and seeded when missing)")
      ->check(DatabaseFileName())
      ->capture_default_str();
  lookup->callback([args] { Lookup(*args); });
}

const CommandRegistration keys_registration{"keys", &AddKeysCommand};

}  // namespace
}  // namespace pintag::cli

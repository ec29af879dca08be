// India Post CSV rows into the importer, over an unseeded registry (a seeded one costs a second
// an import in key probing, far too slow to fuzz): the CSV reader, the header
// detection, row checks and the one-transaction write. Two inputs in three get a valid header in
// front (the first byte decides), so the fuzzer spends its time on rows, not on headers.
// Every import must end in a report or an error value, and the database must stay consistent:
// every pincode keeps exactly one key; an import refused (an error, or strict with a bad row)
// leaves the registry's rows and version as they were. Each input starts from the same empty
// registry (DatabaseReset), so a saved input replays as it ran.

#include <stdlib.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "fuzz_support.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/importer.hpp"
#include "pintag/db/snapshot.hpp"

namespace {

constexpr const char* kNewerHeader =
    "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
    "statename,latitude,longitude\n";
constexpr const char* kOlderHeader =
    "officename,pincode,officeType,Deliverystatus,divisionname,regionname,circlename,Taluk,"
    "Districtname,statename\n";

pintag::db::Connection& Connection() {
  static pintag::db::Connection connection = [] {
    std::string dir = (std::filesystem::temp_directory_path() / "pintag-fuzz-csv-XXXXXX").string();
    if (::mkdtemp(dir.data()) == nullptr) std::abort();
    pintag::fuzz::RemoveDirectoryAtExit(dir);
    auto opened = pintag::db::OpenDatabase(dir + "/registry.db", {.create = true, .seed = false});
    if (!opened) std::abort();
    return std::move(opened.value().connection);
  }();
  return connection;
}

void ResetDatabase() {
  static pintag::fuzz::DatabaseReset reset(Connection().path());
  reset();
}

/// What an import writes, to tell an import that changed nothing: the version counts every
/// committed change (an office updated in place too), the row counts what was added.
std::string Fingerprint() {
  pintag::db::Connection& c = Connection();
  const auto version = pintag::db::RegistryVersion(c);
  if (!version) std::abort();
  return std::to_string(*version) + " " +
         std::to_string(c.queryInt64("SELECT count(*) FROM pincodes")) + " " +
         std::to_string(c.queryInt64("SELECT count(*) FROM tag_keys")) + " " +
         std::to_string(c.queryInt64("SELECT count(*) FROM offices"));
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ResetDatabase();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  ResetDatabase();
  std::string csv;
  if (data[0] % 3 == 1) csv = kNewerHeader;
  if (data[0] % 3 == 2) csv = kOlderHeader;
  csv.append(reinterpret_cast<const char*>(data) + 1, size - 1);
  pintag::db::ImportOptions options;
  options.strict = (data[0] & 0x80) != 0;
  const std::string before = Fingerprint();
  auto report = pintag::db::ImportDirectoryCsv(Connection(), csv, options);
  // Checked in the database, not taken from the report's own `applied`.
  const bool refused = !report || (options.strict && report->bad_rows > 0);
  if (refused && Fingerprint() != before) std::abort();
  if (report && report->applied == refused) std::abort();
  if (pintag::fuzz::ExpectSuccess() && (refused || report->bad_rows > 0)) {
    std::fprintf(stderr, "expected a clean import, got %s\n",
                 report ? "bad rows" : report.error().message.c_str());
    std::abort();
  }
  // Every pincode has its key (and a key row has its pincode by its foreign key).
  const std::int64_t keyless = Connection().queryInt64(
      "SELECT count(*) FROM pincodes LEFT JOIN tag_keys USING (pincode) "
      "WHERE tag_keys.pincode IS NULL");
  if (keyless != 0) std::abort();
  return 0;
}

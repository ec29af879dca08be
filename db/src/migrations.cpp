// Schema migrations, numbered from 1. Each step runs with its version bump in one transaction.
// Never edit a released step: add a new one.

#include <string>

#include "guard.hpp"
#include "pintag/db/database.hpp"
#include "schema.hpp"
#include "sort_plan_internal.hpp"

namespace pintag::db {
namespace detail {
namespace {

constexpr const char* kVersion1 = R"sql(
CREATE TABLE pincodes (
  pincode    INTEGER PRIMARY KEY CHECK (pincode BETWEEN 100000 AND 999999),
  status     TEXT NOT NULL DEFAULT 'active' CHECK (status IN ('active', 'retired')),
  added_at   TEXT NOT NULL,
  retired_at TEXT,
  source     TEXT NOT NULL
);
-- The key table is append-only (DESIGN.md section 2): a key once given is never changed, freed or
-- reused; a retired pincode keeps its key.
CREATE TABLE tag_keys (
  pincode      INTEGER PRIMARY KEY REFERENCES pincodes (pincode),
  tag_key      INTEGER NOT NULL UNIQUE CHECK (tag_key BETWEEN 0 AND 32767),
  allocated_at TEXT NOT NULL
);
CREATE TRIGGER tag_keys_append_only_update BEFORE UPDATE ON tag_keys
BEGIN SELECT RAISE(ABORT, 'the key table is append-only'); END;
CREATE TRIGGER tag_keys_append_only_delete BEFORE DELETE ON tag_keys
BEGIN SELECT RAISE(ABORT, 'the key table is append-only'); END;
CREATE TABLE offices (
  id          INTEGER PRIMARY KEY,
  pincode     INTEGER NOT NULL REFERENCES pincodes (pincode),
  name        TEXT NOT NULL CHECK (length(name) > 0),
  branch_type TEXT,
  delivery    TEXT,
  division    TEXT NOT NULL,
  region      TEXT NOT NULL,
  circle      TEXT NOT NULL,
  district    TEXT NOT NULL,
  state       TEXT NOT NULL,
  taluk       TEXT,
  latitude    REAL,
  longitude   REAL,
  source      TEXT NOT NULL,
  updated_at  TEXT NOT NULL
);
CREATE UNIQUE INDEX offices_pincode_name ON offices (pincode, name);
CREATE INDEX offices_name ON offices (name COLLATE NOCASE);
CREATE INDEX offices_district ON offices (district COLLATE NOCASE);
CREATE INDEX offices_state ON offices (state COLLATE NOCASE);
)sql";

constexpr const char* kVersion2 = R"sql(
CREATE TABLE sort_plans (
  id           INTEGER PRIMARY KEY,
  name         TEXT NOT NULL UNIQUE,
  fallback_bin TEXT NOT NULL,
  description  TEXT NOT NULL DEFAULT '',
  updated_at   TEXT NOT NULL
);
CREATE TABLE sort_rules (
  plan_id INTEGER NOT NULL REFERENCES sort_plans (id) ON DELETE CASCADE,
  prefix  TEXT NOT NULL CHECK (length(prefix) BETWEEN 1 AND 6 AND prefix NOT GLOB '*[^0-9]*'),
  bin     TEXT NOT NULL,
  PRIMARY KEY (plan_id, prefix)
) WITHOUT ROWID;
CREATE TABLE api_tokens (
  id          INTEGER PRIMARY KEY,
  role        TEXT NOT NULL CHECK (role IN ('admin', 'counter', 'scanner')),
  label       TEXT NOT NULL DEFAULT '',
  salt        BLOB NOT NULL,
  secret_hash BLOB NOT NULL,
  created_at  TEXT NOT NULL,
  revoked_at  TEXT
);
CREATE TABLE scan_log (
  id           INTEGER PRIMARY KEY,
  scanned_at   TEXT NOT NULL,
  token_id     INTEGER REFERENCES api_tokens (id),
  image_bytes  INTEGER NOT NULL CHECK (image_bytes >= 0),
  image_width  INTEGER,
  image_height INTEGER,
  result_json  TEXT NOT NULL CHECK (json_valid(result_json))
);
CREATE INDEX scan_log_token ON scan_log (token_id, id);
)sql";

void Step2(Connection& connection) {
  connection.execute(kVersion2);
  // A file seeded at version 1 gets the default plan the seed now ships with.
  if (connection.queryInt64("SELECT count(*) FROM pincodes") > 0) InsertDefaultPlan(connection);
}

// Version 3: a `replica` role for the servers that pull registry snapshots. SQLite cannot alter a
// CHECK constraint, so the table is rebuilt; scan_log rows reference it, and deferring foreign
// keys to the commit lets the parent rows be dropped and put back within the step.
constexpr const char* kVersion3 = R"sql(
PRAGMA defer_foreign_keys = ON;
CREATE TEMP TABLE api_tokens_v2 AS SELECT * FROM api_tokens;
DROP TABLE api_tokens;
CREATE TABLE api_tokens (
  id          INTEGER PRIMARY KEY,
  role        TEXT NOT NULL CHECK (role IN ('admin', 'counter', 'scanner', 'replica')),
  label       TEXT NOT NULL DEFAULT '',
  salt        BLOB NOT NULL,
  secret_hash BLOB NOT NULL,
  created_at  TEXT NOT NULL,
  revoked_at  TEXT
);
INSERT INTO api_tokens (id, role, label, salt, secret_hash, created_at, revoked_at)
  SELECT id, role, label, salt, secret_hash, created_at, revoked_at FROM temp.api_tokens_v2;
DROP TABLE temp.api_tokens_v2;
)sql";

// Version 4: the registry version, one counter that every committed change to what a replica
// serves (pincodes, keys, offices, sort plans, tokens) increases. Snapshots carry it; replicas
// compare it. Triggers, not the query functions, bump it, so the CLI, the importer and any
// other writer count too (a per-row trigger costs about 0.5 s of the 2-3 s seed). The scan log
// is not part of it: each server keeps its own.
constexpr const char* kVersion4Table = R"sql(
CREATE TABLE registry_version (
  id      INTEGER PRIMARY KEY CHECK (id = 1),
  version INTEGER NOT NULL CHECK (version >= 1)
);
INSERT INTO registry_version (id, version) VALUES (1, 1);
)sql";

constexpr const char* kVersionedTables[] = {"pincodes",   "tag_keys",   "offices",
                                            "sort_plans", "sort_rules", "api_tokens"};

void Step4(Connection& connection) {
  connection.execute(kVersion4Table);
  struct Event {
    const char* name;
    const char* sql;
  };
  for (const char* table : kVersionedTables) {
    for (const Event event :
         {Event{"insert", "INSERT"}, Event{"update", "UPDATE"}, Event{"delete", "DELETE"}}) {
      connection.execute(std::string("CREATE TRIGGER ") + table + "_" + event.name +
                         "_bumps_registry_version AFTER " + event.sql + " ON " + table +
                         " BEGIN UPDATE registry_version SET version = version + 1; END;");
    }
  }
}

// Version 5: the key table's append-only triggers missed INSERT OR REPLACE, whose delete of the
// row in the way fires no DELETE trigger (unless recursive_triggers is on, which a sqlite3 shell
// does not set): `INSERT OR REPLACE INTO tag_keys VALUES (110002, <110001's key>, …)` gave
// 110001's key to another pincode and left 110001 without one, a misroute on every label printed
// before. An insert that meets an existing pincode or key is refused before any conflict
// resolution runs; a new pincode with a new key goes in as before.
constexpr const char* kVersion5 = R"sql(
CREATE TRIGGER tag_keys_append_only_insert BEFORE INSERT ON tag_keys
WHEN EXISTS (SELECT 1 FROM tag_keys WHERE pincode = NEW.pincode OR tag_key = NEW.tag_key)
BEGIN SELECT RAISE(ABORT, 'the key table is append-only'); END;
)sql";

struct Migration {
  int version;
  void (*apply)(Connection&);
};

constexpr Migration kMigrations[] = {
    {1, [](Connection& c) { c.execute(kVersion1); }}, {2, &Step2},
    {3, [](Connection& c) { c.execute(kVersion3); }}, {4, &Step4},
    {5, [](Connection& c) { c.execute(kVersion5); }},
};
static_assert(std::size(kMigrations) == kSchemaVersion);

}  // namespace

void ApplyMigrations(Connection& connection, int from, int target) {
  for (const Migration& migration : kMigrations) {
    if (migration.version <= from || migration.version > target) continue;
    migration.apply(connection);
    connection.execute("PRAGMA user_version = " + std::to_string(migration.version));
  }
}

}  // namespace detail

int SchemaVersion(Connection& connection) {
  return static_cast<int>(connection.queryInt64("PRAGMA user_version"));
}

void MigrateTo(Connection& connection, int target) {
  while (true) {
    Transaction transaction(connection);
    // Read inside the write lock: another process may have migrated meanwhile.
    const int version = SchemaVersion(connection);
    if (version >= target) return;
    detail::ApplyMigrations(connection, version, version + 1);
    transaction.commit();
  }
}

}  // namespace pintag::db

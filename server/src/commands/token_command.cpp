// `pintag token create|list|revoke`: API tokens for the HTTP server.

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "commands/commands.hpp"
#include "commands/open_db.hpp"
#include "commands/option_checks.hpp"
#include "commands/unseen_token.hpp"
#include "pintag/db/csv.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/text.hpp"
#include "pintag/db/tokens.hpp"

namespace pintag::cli {
namespace {

struct TokenArgs {
  std::string db = "pintag.db";
  std::string role;
  std::string label;
  std::string out;  ///< a file for the secret instead of stdout
  std::int64_t id = 0;
};

void Create(const TokenArgs& args) {
  const auto role = db::ParseRole(args.role);
  if (!role) throw UsageError("--role must be admin, counter, scanner or replica");
  // Checked as CreateToken checks it, before the database is opened: a bad label must not create
  // and seed one.
  if (auto error = db::CheckTokenLabel(args.label)) {
    throw UsageError("--" + error->message);
  }
  // A mistyped path, one that cannot be written, or a database: no token is made for it, and no
  // database made or seeded.
  if (!args.out.empty()) CheckSecretFile("--out", args.out, args.db);
  db::Connection connection = OpenDb(args.db);
  auto token = db::CreateToken(connection, *role, args.label);
  if (!token && token.error().code == db::ErrorCode::kBusy) {
    throw std::runtime_error(LockedMessage(args.db, "no token was made"));
  }
  if (!token) {
    const std::string failure = DatabaseWriteFailure(args.db, token.error(), "no token was made");
    throw std::runtime_error(failure.empty() ? token.error().message : failure);
  }
  if (!args.out.empty()) {
    RevokeIfUnwritten(connection, token->info.id, args.out,
                      WriteSecretFile(args.out, token->secret));
    std::cerr << "token " << token->info.id << " (" << db::ToString(*role) << "); its secret is in "
              << args.out << " (mode 0600), and shown nowhere else\n";
    return;
  }
  std::cerr << "token " << token->info.id << " (" << db::ToString(*role)
            << "); the secret below is shown only now:\n";
  std::cout << token->secret << "\n" << std::flush;
  RevokeIfStdoutFailed(connection, token->info.id);
}

void List(const TokenArgs& args) {
  db::Connection connection = OpenForReading(args.db, /*must_exist=*/true);
  auto tokens = db::ListTokens(connection);
  if (!tokens) throw std::runtime_error(tokens.error().message);
  std::cout << "id,role,label,created_at,revoked_at\n";
  for (const db::TokenInfo& t : *tokens) {
    std::cout << t.id << "," << db::ToString(t.role) << "," << db::CsvTextField(t.label) << ","
              << t.created_at << "," << t.revoked_at.value_or("") << "\n";
  }
}

void Revoke(const TokenArgs& args) {
  db::Connection connection = OpenExistingDb(args.db);
  // Said apart from a revocation made now: a script revoking a leaked token must not read an
  // old revocation as its own.
  if (auto before = db::GetToken(connection, args.id); before && before->revoked_at) {
    std::cout << "token " << before->id << " was already revoked at " << *before->revoked_at
              << "\n";
    return;
  }
  auto token = db::RevokeToken(connection, args.id);
  if (!token && token.error().code == db::ErrorCode::kBusy) {
    throw std::runtime_error(LockedMessage(args.db, "the token was not revoked"));
  }
  if (!token) {
    const std::string failure =
        DatabaseWriteFailure(args.db, token.error(), "the token was not revoked");
    throw std::runtime_error(failure.empty() ? token.error().message : failure);
  }
  std::cout << "token " << token->id << " revoked at " << token->revoked_at.value_or("?") << "\n";
}

void AddTokenCommand(CLI::App& app) {
  auto args = std::make_shared<TokenArgs>();
  CLI::App* token = app.add_subcommand("token", "API tokens for the HTTP server");
  token->require_subcommand(1);
  const auto add_db = [&](CLI::App* cmd, const char* description) {
    cmd->add_option("--db", args->db, description)
        ->check(DatabaseFileName())
        ->capture_default_str();
  };

  CLI::App* create = token->add_subcommand("create", "Create a token and print its secret once");
  create->add_option("--role", args->role, "admin, counter, scanner or replica")->required();
  create->add_option("--label", args->label, "a note on who or what uses it");
  create
      ->add_option("--out", args->out,
                   "write the secret to this file (mode 0600, replaced whole) instead of "
                   "stdout, e.g. a replica's --follow-token-file")
      ->check(FileName());
  add_db(create, "database file (created and seeded when missing)");
  create->callback([args] { Create(*args); });

  CLI::App* list =
      token->add_subcommand("list",
                            "List tokens (never their secrets) as CSV; a label starting with = + - "
                            "or @ is printed after a ' so that a spreadsheet shows it as text");
  add_db(list, "database file (must exist)");
  list->callback([args] { List(*args); });

  CLI::App* revoke = token->add_subcommand("revoke", "Revoke a token by id");
  // Checked before the database is opened, as the HTTP route checks it: a token id is positive.
  // DecimalInteger has read the text before this check (AddRegisteredCommands), so it is plain
  // decimal digits, a minus perhaps, and 0 is "0".
  revoke->add_option("id", args->id, "token id")
      ->required()
      ->check(CLI::Validator(
          [](const std::string& text) -> std::string {
            return text.front() == '-' || text == "0"
                       ? "a token id is a positive integer, got '" + text + "'"
                       : "";
          },
          ""));
  add_db(revoke, "database file (must exist)");
  revoke->callback([args] { Revoke(*args); });
}

const CommandRegistration token_registration{"token", &AddTokenCommand};

}  // namespace
}  // namespace pintag::cli

#include "commands/open_db.hpp"

#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <utility>

#include "pintag/db/database.hpp"

namespace pintag::cli {

db::Connection OpenDb(const std::string& path) {
  auto opened = db::OpenDatabase(path);
  if (!opened) throw std::runtime_error(opened.error().message);
  if (opened->created) {
    std::cerr << "created " << path << " and seeded it from " << db::SeedSource() << "\n";
  }
  return std::move(opened).value().connection;
}

db::Connection OpenExistingDb(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    throw std::runtime_error(
        "no database at " + path +
        " (`pintag serve`, `pintag import` or `pintag token create` makes one)");
  }
  return OpenDb(path);
}

}  // namespace pintag::cli

#include "commands/open_db.hpp"

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

}  // namespace pintag::cli

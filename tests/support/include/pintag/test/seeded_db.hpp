#pragma once
// A database seeded from the bundled registry, made once and copied by every test that needs
// one (seeding takes seconds; copying the file takes milliseconds).

#include <string>

namespace pintag::test {

/// The path of a seeded, migrated database; do not modify it. ctest runs every test in its own
/// process, so the file is cached in `cache_dir` under the test executable's modification time:
/// a rebuilt executable (new seed, new schema) never sees an old one, and older templates in
/// `cache_dir` are removed. Give each test executable its own `cache_dir`. With an empty
/// `cache_dir` the template is seeded into a directory of this process.
std::string SeededTemplate(const std::string& cache_dir);

}  // namespace pintag::test

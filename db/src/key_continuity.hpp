#pragma once
// A registry that replaces another must keep every key the other gave: labels printed with a
// key stay in circulation, and a key that now names another pincode misroutes each of them
// (DESIGN.md section 2: a key is never reused). Only a primary restored from an older backup
// breaks this, by giving the keys it lost to the next pincodes it adds.

#include <string>

namespace pintag::db {

/// Empty when the registry at `received` gives every key of the registry at `current` to the
/// same pincode; else what it loses or gives to another pincode, the first few named. Both are
/// opened read-only; throws SqliteError when either cannot be read.
std::string KeysNotKept(const std::string& current, const std::string& received);

}  // namespace pintag::db

#pragma once
// An office in the test district, for pincodes a test adds straight to a database file.

#include <string>

#include "pintag/db/registry.hpp"

namespace pintag::test {

inline db::PostOffice TestOffice(const std::string& name) {
  db::PostOffice office;
  office.name = name;
  office.district = "Testpur";
  office.state = "Test State";
  office.circle = "Test";
  office.region.assign(1, 'T');  // not = "T": GCC 12 warns falsely on a 1-character assign
  office.division = "TD";
  return office;
}

}  // namespace pintag::test

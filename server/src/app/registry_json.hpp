#pragma once
// Registry records as the API shows them: a pincode with its offices (GET /api/v1/pincodes/{pin},
// /keys/{key}, search hits) and the office a label names.

#include <nlohmann/json.hpp>

#include "pintag/codec/pincode.hpp"
#include "pintag/db/registry.hpp"

namespace pintag::app {

/// The office a label names: the head office, else a sub office, else the first office.
const db::PostOffice* MainOffice(const db::PincodeRecord& record);

nlohmann::json OfficeJson(const db::PostOffice& office, Pincode pincode);
/// A pincode as GET /api/v1/pincodes/{pin} answers it.
nlohmann::json RecordJson(const db::PincodeRecord& record);

}  // namespace pintag::app

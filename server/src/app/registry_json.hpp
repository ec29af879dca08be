#pragma once
// Registry records as the API shows them: a pincode with its offices (GET /api/v1/pincodes/{pin},
// /keys/{key}, search hits) and the office a label names. Written straight to text (JsonWriter):
// these are the hottest answers the server gives.

#include <string>

#include "pintag/codec/pincode.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/server/json_writer.hpp"

namespace pintag::app {

/// One office, in the field names of api.postalpincode.in's PostOffice (snake case).
void WriteOffice(server::JsonWriter& out, const db::PostOffice& office, Pincode pincode);
/// A pincode as GET /api/v1/pincodes/{pin} answers it.
std::string RecordJson(const db::PincodeRecord& record);
/// A page of office search hits as GET /api/v1/pincodes?q= answers it.
std::string SearchPageJson(const db::SearchPage& page);

}  // namespace pintag::app

#include "app/registry_json.hpp"

namespace pintag::app {

const db::PostOffice* MainOffice(const db::PincodeRecord& record) {
  for (const char* type : {"HO", "SO"}) {
    for (const db::PostOffice& office : record.offices) {
      if (office.branch_type == type) return &office;
    }
  }
  return record.offices.empty() ? nullptr : &record.offices.front();
}

namespace {

template <typename T>
nlohmann::json Optional(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json OfficeJson(const db::PostOffice& office, Pincode pincode) {
  return {{"name", office.name},
          {"branch_type", Optional(office.branch_type)},
          {"delivery", Optional(office.delivery)},
          {"circle", office.circle},
          {"region", office.region},
          {"division", office.division},
          {"district", office.district},
          {"state", office.state},
          {"taluk", Optional(office.taluk)},
          {"latitude", Optional(office.latitude)},
          {"longitude", Optional(office.longitude)},
          {"country", "India"},
          {"pincode", pincode.str()}};
}

nlohmann::json RecordJson(const db::PincodeRecord& record) {
  nlohmann::json offices = nlohmann::json::array();
  for (const db::PostOffice& office : record.offices)
    offices.push_back(OfficeJson(office, record.pincode));
  const db::PostOffice* main = MainOffice(record);
  return {{"pincode", record.pincode.str()},
          {"key", record.key.value()},
          {"status", db::ToString(record.status)},
          {"office", main ? nlohmann::json(main->name) : nlohmann::json(nullptr)},
          {"district", record.district},
          {"state", record.state},
          {"circle", record.circle},
          {"region", record.region},
          {"division", record.division},
          {"added_at", record.added_at},
          {"retired_at", Optional(record.retired_at)},
          {"key_allocated_at", record.key_allocated_at},
          {"office_count", record.offices.size()},
          {"offices", std::move(offices)}};
}

}  // namespace pintag::app

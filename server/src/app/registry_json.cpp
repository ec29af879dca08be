#include "app/registry_json.hpp"

namespace pintag::app {

using server::JsonWriter;

void WriteOffice(JsonWriter& out, const db::PostOffice& office, Pincode pincode) {
  out.beginObject();
  out.key("name").value(office.name);
  out.key("branch_type").value(office.branch_type);
  out.key("delivery").value(office.delivery);
  out.key("circle").value(office.circle);
  out.key("region").value(office.region);
  out.key("division").value(office.division);
  out.key("district").value(office.district);
  out.key("state").value(office.state);
  out.key("taluk").value(office.taluk);
  out.key("latitude").value(office.latitude);
  out.key("longitude").value(office.longitude);
  out.key("country").value("India");
  out.key("pincode").value(pincode.str());
  out.endObject();
}

std::string RecordJson(const db::PincodeRecord& record) {
  JsonWriter out;
  out.beginObject();
  out.key("pincode").value(record.pincode.str());
  out.key("key").value(record.key.value());
  out.key("status").value(db::ToString(record.status));
  const db::PostOffice* main = db::MainOffice(record);
  out.key("office");
  if (main != nullptr) {
    out.value(main->name);
  } else {
    out.null();
  }
  out.key("district").value(record.district);
  out.key("state").value(record.state);
  out.key("circle").value(record.circle);
  out.key("region").value(record.region);
  out.key("division").value(record.division);
  out.key("added_at").value(record.added_at);
  out.key("retired_at").value(record.retired_at);
  out.key("key_allocated_at").value(record.key_allocated_at);
  out.key("office_count").value(record.offices.size());
  out.key("offices").beginArray();
  for (const db::PostOffice& office : record.offices) WriteOffice(out, office, record.pincode);
  out.endArray();
  out.endObject();
  return out.take();
}

std::string SearchPageJson(const db::SearchPage& page) {
  JsonWriter out;
  out.beginObject();
  out.key("total").value(page.total);
  out.key("limit").value(page.limit);
  out.key("offset").value(page.offset);
  out.key("results").beginArray();
  for (const db::OfficeHit& hit : page.hits) {
    out.beginObject();
    out.key("pincode").value(hit.pincode.str());
    out.key("key").value(hit.key.value());
    out.key("status").value(db::ToString(hit.status));
    out.key("office");
    WriteOffice(out, hit.office, hit.pincode);
    out.endObject();
  }
  out.endArray();
  out.endObject();
  return out.take();
}

}  // namespace pintag::app

-- wrk: mixed PinTag traffic through nginx, every answer checked. One connection per thread
-- (wrk -t N -c N), so each response belongs to the request this thread sent last.
--   PINTAG_COUNTER, PINTAG_SCANNER  tokens;  PINTAG_PHOTO  a JPEG holding the tag of 110001
local counter = os.getenv("PINTAG_COUNTER")
local scanner = os.getenv("PINTAG_SCANNER")
local file = assert(io.open(os.getenv("PINTAG_PHOTO"), "rb"))
local photo = file:read("*a")
file:close()

-- kind: method, path, headers, body, expected status, text the body must hold
local kinds = {
  {"GET", "/api/v1/pincodes/110001", {}, nil, 200, '"key":11684'},
  {"GET", "/api/v1/route/560001?plan=default", {}, nil, 200, '"bin":"56"'},
  {"GET", "/api/v1/labels/560001.png?dpi=72", {Authorization = "Bearer " .. counter}, nil, 200,
   "PNG"},
  {"POST", "/api/v1/detect", {Authorization = "Bearer " .. scanner,
                              ["Content-Type"] = "image/jpeg"}, photo, 200,
   '"pincode":"110001"'},
  {"GET", "/api/v1/pincodes/999999", {}, nil, 404, "Unknown Pincode"},
}
local only = tonumber(os.getenv("PINTAG_ONLY_KIND") or "")  -- e.g. 4: detections only

local threads = {}
function setup(thread)
  table.insert(threads, thread)
end

function init(args)
  sent, wrong, turn = 0, 0, 0
  first_wrong = ""
end

function request()
  turn = turn + 1
  current = only or ((turn - 1) % #kinds + 1)
  local k = kinds[current]
  sent = sent + 1
  return wrk.format(k[1], k[2], k[3], k[4])
end

function response(status, headers, body)
  local k = kinds[current]
  if status ~= k[5] or not string.find(body, k[6], 1, true) then
    wrong = wrong + 1
    if first_wrong == "" then first_wrong = k[2] .. " -> " .. status .. " " .. body:sub(1, 200) end
  end
end

function done(summary, latency, requests)
  local total_wrong, total_sent, example = 0, 0, ""
  for _, thread in ipairs(threads) do
    total_wrong = total_wrong + thread:get("wrong")
    total_sent = total_sent + thread:get("sent")
    if example == "" then example = thread:get("first_wrong") end
  end
  local e = summary.errors
  io.write(string.format(
    "pintag-load completed=%d wrong=%d socket_errors=%d timeouts=%d rps=%.1f p50_ms=%.1f p99_ms=%.1f\n",
    summary.requests, total_wrong, e.connect + e.read + e.write, e.timeout,
    summary.requests / (summary.duration / 1e6), latency:percentile(50) / 1000,
    latency:percentile(99) / 1000))
  if example ~= "" then io.write("pintag-load first wrong answer: " .. example .. "\n") end
end

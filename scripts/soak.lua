-- wrk: the soak's mixed traffic against one `pintag serve`, every answer checked (scripts/soak.sh).
-- One connection per wrk thread (wrk -t N -c N), so each answer belongs to this thread's last
-- request. PINTAG_COUNTER, PINTAG_SCANNER: tokens; PINTAG_PHOTO: a 1080p JPEG holding 110001's tag.
local counter = os.getenv("PINTAG_COUNTER")
local scanner = os.getenv("PINTAG_SCANNER")
local file = assert(io.open(os.getenv("PINTAG_PHOTO"), "rb"))
local photo = file:read("*a")
file:close()

local pins = {"110001", "560001", "400001", "700001", "600001", "500001", "302001", "682001"}
local queries = {"delhi", "bangalore", "Mumbai", "kolkata", "chennai", "pune"}
local auth_counter = {Authorization = "Bearer " .. counter}

-- kind: a function of the turn giving method, path, headers, body; expected status; text the
-- body must hold. Ten kinds, so a detection is one request in ten.
local kinds = {
  function(n) return "GET", "/api/v1/pincodes/" .. pins[n % #pins + 1], {}, nil, 200, '"key":' end,
  function(n) return "GET", "/api/v1/pincodes/" .. pins[(n + 3) % #pins + 1], {}, nil, 200, '"key":' end,
  function(n) return "GET", "/api/v1/keys/11684", {}, nil, 200, '"110001"' end,
  function(n) return "GET", "/api/v1/pincodes?q=" .. queries[n % #queries + 1] .. "&limit=10", {}, nil, 200, '"pincode"' end,
  function(n) return "GET", "/api/v1/route/" .. pins[n % #pins + 1] .. "?plan=default", {}, nil, 200, '"bin"' end,
  function(n) return "GET", "/api/v1/labels/" .. pins[n % #pins + 1] .. ".pdf", auth_counter, nil, 200, "%PDF" end,
  function(n) return "GET", "/api/v1/labels/" .. pins[n % #pins + 1] .. ".png?dpi=150", auth_counter, nil, 200, "PNG" end,
  function(n) return "GET", "/api/v1/pincodes/" .. pins[(n + 5) % #pins + 1], {}, nil, 200, '"key":' end,
  function(n)
    return "POST", "/api/v1/detect", {Authorization = "Bearer " .. scanner,
                                     ["Content-Type"] = "image/jpeg"}, photo, 200,
           '"pincode":"110001"'
  end,
  function(n) return "GET", "/api/v1/pincodes?q=" .. queries[(n + 2) % #queries + 1] .. "&limit=5", {}, nil, 200, '"pincode"' end,
}

local threads = {}
function setup(thread)
  thread:set("id", #threads)
  table.insert(threads, thread)
end

function init(args)
  sent, wrong, turn = 0, 0, id or 0
  first_wrong = ""
end

function request()
  turn = turn + 1
  local method, path, headers, body, status, text = kinds[turn % #kinds + 1](turn)
  expect_status, expect_text, last_path = status, text, path
  sent = sent + 1
  return wrk.format(method, path, headers, body)
end

function response(status, headers, body)
  if status ~= expect_status or not string.find(body, expect_text, 1, true) then
    wrong = wrong + 1
    if first_wrong == "" then first_wrong = last_path .. " -> " .. status .. " " .. body:sub(1, 2000) end
  end
end

function done(summary, latency, requests)
  local total_wrong, example = 0, ""
  for _, thread in ipairs(threads) do
    total_wrong = total_wrong + thread:get("wrong")
    if example == "" then example = thread:get("first_wrong") end
  end
  local e = summary.errors
  io.write(string.format(
    "soak-result requests=%d wrong=%d http_errors=%d socket_errors=%d timeouts=%d rps=%.1f " ..
    "mean_ms=%.1f p50_ms=%.1f p90_ms=%.1f p99_ms=%.1f max_ms=%.1f\n",
    summary.requests, total_wrong, e.status, e.connect + e.read + e.write, e.timeout,
    summary.requests / (summary.duration / 1e6), latency.mean / 1000,
    latency:percentile(50) / 1000, latency:percentile(90) / 1000, latency:percentile(99) / 1000,
    latency.max / 1000))
  if example ~= "" then io.write("soak-first-wrong " .. example .. "\n") end
end

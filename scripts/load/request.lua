-- wrk script for scripts/load.sh: one kind of request, every answer checked, latency summarised.
--   PINTAG_METHOD, PINTAG_PATH   the request (GET by default)
--   PINTAG_TOKEN                 bearer token, if the route needs one
--   PINTAG_BODIES                a file listing body files (one path a line, sent in rotation,
--                                as image/jpeg); none: no body
--   PINTAG_EXPECT                status every answer must have (default 200)
-- Prints one line: pintag-load name=… rps=… mean_ms=… p90_ms=… p99_ms=… max_ms=… wrong=… errors=…
local method = os.getenv("PINTAG_METHOD") or "GET"
local path = assert(os.getenv("PINTAG_PATH"), "PINTAG_PATH is required")
local token = os.getenv("PINTAG_TOKEN")
local expect = tonumber(os.getenv("PINTAG_EXPECT") or "200")
local name = os.getenv("PINTAG_NAME") or path

local bodies = {}
local list = os.getenv("PINTAG_BODIES")
if list and list ~= "" then
  for line in io.lines(list) do
    local f = assert(io.open(line, "rb"))
    table.insert(bodies, f:read("*a"))
    f:close()
  end
end

local headers = {}
if token and token ~= "" then headers["Authorization"] = "Bearer " .. token end
if #bodies > 0 then headers["Content-Type"] = "image/jpeg" end

local threads = {}
function setup(thread)
  thread:set("id", #threads)
  table.insert(threads, thread)
end

-- Every request is formatted once per thread, not once per send: building a request string of a
-- few hundred kilobytes each time cost wrk CPU that the server, on the same cores, then lacked.
local requests = {}

function init(args)
  wrong, turn = 0, id or 0
  first_wrong = ""
  if #bodies == 0 then
    requests[1] = wrk.format(method, path, headers)
  else
    for i, body in ipairs(bodies) do requests[i] = wrk.format(method, path, headers, body) end
  end
end

function request()
  -- Threads start at different frames, so the set is mixed from the first second.
  turn = turn + 1
  return requests[(turn * 7) % #requests + 1]
end

function response(status, hdrs, body)
  if status ~= expect then
    wrong = wrong + 1
    if first_wrong == "" then first_wrong = status .. " " .. body:sub(1, 200) end
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
    "pintag-load name=%s requests=%d rps=%.1f mean_ms=%.2f p90_ms=%.2f p99_ms=%.2f max_ms=%.2f wrong=%d errors=%d\n",
    name, summary.requests, summary.requests / (summary.duration / 1e6), latency.mean / 1000,
    latency:percentile(90) / 1000, latency:percentile(99) / 1000, latency.max / 1000,
    total_wrong, e.connect + e.read + e.write + e.status + e.timeout))
  if example ~= "" then io.write("pintag-load first wrong answer: " .. example .. "\n") end
end

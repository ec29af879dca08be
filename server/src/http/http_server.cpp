// Adapts cpp-httplib 0.11.4 to Api; with connection_stream.cpp, the only files that include
// httplib.h.
//
// Connections: cpp-httplib's own loop over a connection's requests is replaced by one that reads
// through ConnectionStream, which stops reading a request whose head does not end (431).
//
// Order of a request in cpp-httplib: headers are read, the pre-routing handler runs (here: route,
// auth, declared length and type, via Api::admit; a request with no body is answered there),
// then the body is read and the handler runs,
// then the error handler (status >= 400) and the logger. All of it on one worker thread, so the
// admission is carried from the pre-routing handler to the handler and logger in a thread_local.
//
// Bodies: cpp-httplib 0.11.4 applies set_payload_max_length only to bodies with a Content-Length
// (a chunked body is read without limit), so POST/PUT/PATCH/DELETE use content-reader handlers
// that count every chunk, and GET/HEAD/OPTIONS requests that announce a body are refused before
// it is read.

#include "pintag/server/http_server.hpp"

#include <httplib.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <optional>
#include <string_view>
#include <thread>

#include "connection_stream.hpp"
#include "idle_connections.hpp"
#include "pintag/server/header_text.hpp"
#include "pintag/server/listen_check.hpp"
#include "pintag/server/log.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::server {
namespace {

struct RequestState {
  bool active = false;
  std::chrono::steady_clock::time_point start;
  Admission admission;
  std::string request_id;
  bool admitted_before_continue = false;  ///< preRoute ran from the Expect: 100-continue handler
};
thread_local RequestState t_state;

void Apply(const HttpResponse& from, httplib::Response& to) {
  to.status = from.status;
  for (const auto& [name, value] : from.headers) to.set_header(name, value);
  to.set_content(from.body, from.content_type);
}

/// The headers the client sent. cpp-httplib 0.11.4 adds four of its own (REMOTE_ADDR and the
/// like) to a request's headers, which made the 100-header limit 96 of the client's.
HeaderMap Headers(const httplib::Request& req) {
  static const std::array<std::string_view, 4> kAddedByHttplib = {"REMOTE_ADDR", "REMOTE_PORT",
                                                                  "LOCAL_ADDR", "LOCAL_PORT"};
  HeaderMap headers;
  for (const auto& [name, value] : req.headers) {
    if (std::find(kAddedByHttplib.begin(), kAddedByHttplib.end(), name) == kAddedByHttplib.end()) {
      headers.emplace(name, value);
    }
  }
  return headers;
}

/// The path of an absolute-form target ("http://host:8080/api/v1/keys/1" -> "/api/v1/keys/1"),
/// or nothing when `target` is not one. The authority is not kept: nothing here is routed by host.
std::optional<std::string> OriginFormPath(std::string_view target) {
  for (const std::string_view scheme : {"http://", "https://"}) {
    if (target.size() >= scheme.size() && Lower(target.substr(0, scheme.size())) == scheme) {
      const std::string_view rest = target.substr(scheme.size());
      const std::size_t slash = rest.find('/');
      return slash == std::string_view::npos ? std::string("/") : std::string(rest.substr(slash));
    }
  }
  return std::nullopt;
}

/// The query of the request target `target`, split as a browser's URLSearchParams splits it:
/// pieces at '&', each a name and a value at its first '=', then decoded ('+' a space).
/// cpp-httplib 0.11.4 splits a piece at every '=' and keeps the last part ("fx=1000=2000" gave
/// fx 2000), and keeps one of two identical pieces, so a parameter given twice passed as once.
std::multimap<std::string, std::string> ParseQuery(const std::string& target) {
  std::multimap<std::string, std::string> query;
  const std::size_t question = target.find('?');
  if (question == std::string::npos) return query;
  std::string_view rest = std::string_view(target).substr(question + 1);
  while (!rest.empty()) {
    const std::size_t amp = rest.find('&');
    const std::string_view piece = rest.substr(0, amp);
    rest = amp == std::string_view::npos ? std::string_view() : rest.substr(amp + 1);
    if (piece.empty()) continue;
    const std::size_t equals = piece.find('=');
    const std::string_view name = piece.substr(0, equals);
    const std::string_view value =
        equals == std::string_view::npos ? std::string_view() : piece.substr(equals + 1);
    query.emplace(httplib::detail::decode_url(std::string(name), true),
                  httplib::detail::decode_url(std::string(value), true));
  }
  return query;
}

HttpRequest ToRequest(const httplib::Request& req) {
  HttpRequest request;
  request.request_id = t_state.request_id;
  request.method = req.method;
  request.path = req.path;
  request.query = ParseQuery(req.target);
  request.headers = Headers(req);
  return request;
}

/// Bytes of a request's line and headers read before the server stops reading and answers 431.
/// Above what Api::admit takes (100 headers, 64 KiB; a request line of 8 KiB), so a head that
/// ends gets admit's own answer, and one that does not end costs at most this much.
constexpr std::size_t kMaxRequestHeadBytes = std::size_t{96} * 1024;

/// The stream of the request this worker is reading, for the pre-routing and error handlers.
thread_local ConnectionStream* t_connection = nullptr;

HttpResponse HeadTooLarge() {
  return ProblemResponse(431, "the request line and headers ran past " +
                                  std::to_string(kMaxRequestHeadBytes) +
                                  " bytes; at most 100 headers of 64 KiB in all are read");
}

/// Why the head `stream` was reading was refused: its syntax (RequestHeadCheck), or its size.
HttpResponse HeadRefusal(const ConnectionStream& stream) {
  if (const auto& refusal = stream.headRefusal()) {
    return ProblemResponse(refusal->status, refusal->detail);
  }
  if (stream.headTooSlow()) {
    return ProblemResponse(408, "the request line and headers came too slowly: a head over " +
                                    std::to_string(kWorkerTakesHeadBytes / 1024) +
                                    " KiB must be whole within the read timeout of a worker "
                                    "starting to read it");
  }
  return HeadTooLarge();
}

/// The head was refused as it was read (past the budget, its syntax, too slow).
bool HeadRefused(const ConnectionStream& stream) {
  return stream.overBudget() || stream.headRefusal().has_value() || stream.headTooSlow();
}

std::chrono::microseconds Microseconds(time_t seconds, time_t microseconds) {
  return std::chrono::seconds(seconds) + std::chrono::microseconds(microseconds);
}

/// The worker pool cpp-httplib is given (and deletes after shutdown()), which says when it is
/// shutting down, so that no parked connection is handed to it after.
class WorkerPool final : public httplib::TaskQueue {
 public:
  WorkerPool(std::size_t threads, std::function<void()> on_shutdown)
      : pool_(threads), on_shutdown_(std::move(on_shutdown)) {}

  void enqueue(std::function<void()> fn) override { pool_.enqueue(std::move(fn)); }
  void shutdown() override {
    on_shutdown_();
    pool_.shutdown();  // requests in flight finish
  }

 private:
  httplib::ThreadPool pool_;
  std::function<void()> on_shutdown_;
};

/// cpp-httplib's server with its one-request entry point opened (answerRaw), and its connection
/// loop replaced by one that reads through ConnectionStream (the head budget) and parks a
/// connection between requests in IdleConnections instead of waiting in its worker.
class Server : public httplib::Server {
 public:
  using httplib::Server::process_request;

  /// Answers a request whose head was refused (past the budget, or its syntax) before
  /// cpp-httplib could answer it (its request line was still coming): cpp-httplib then writes
  /// nothing.
  std::function<void(ConnectionStream&)> answer_unended_head;

  /// Set before the server listens: where a connection waits between requests.
  IdleConnections* idle = nullptr;
  /// ServerOptions::min_body_rate, for each request's stream.
  std::uint64_t min_body_rate = 0;

  /// As cpp-httplib 0.11.4's loop: up to `left` requests, each read through a new stream, then
  /// the socket is shut and closed. A request not there yet is waited for in `idle`, for at most
  /// keep_alive_timeout_sec_, and this worker is free meanwhile.
  void serveConnection(int sock, std::size_t left) {
    for (; left > 0; --left) {
      if (PeekRequestHead(sock, kMaxRequestHeadBytes) != HeadState::kReady) {
        idle->park(sock, left,
                   IdleConnections::Clock::now() + std::chrono::seconds(keep_alive_timeout_sec_));
        return;
      }
      ConnectionStream stream(sock, Microseconds(read_timeout_sec_, read_timeout_usec_),
                              Microseconds(write_timeout_sec_, write_timeout_usec_),
                              kMaxRequestHeadBytes, min_body_rate);
      t_connection = &stream;
      t_state = RequestState{};  // nothing of the previous request carries over
      bool closed = false;
      const bool ok = process_request(stream, left == 1, closed, nullptr);
      t_connection = nullptr;
      const bool head_refused = HeadRefused(stream);
      if (head_refused && !stream.wasAnswered() && answer_unended_head) {
        answer_unended_head(stream);
      }
      // An answer that asked to close (a refusal that left a body unread, a refused head):
      // cpp-httplib would have read on, taking the unread bytes for the next request.
      if (head_refused || stream.unread() > 0) {
        // Closed there, once the client has stopped sending.
        idle->drain(sock, std::max(kDrainAfterRefusedHead, stream.unread()));
        return;
      }
      if (stream.closeAfterAnswer()) break;  // everything sent was read: nothing to drain
      if (!ok || closed) break;
    }
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
  }

 private:
  bool process_and_close_socket(socket_t sock) override {
    serveConnection(sock, keep_alive_max_count_);
    return true;
  }
};

/// A connection whose client sent `in` and then waits: reads drain `in`, writes fill `out`.
class MemoryStream : public httplib::Stream {
 public:
  explicit MemoryStream(std::string_view in) : in_(in) {}
  bool is_readable() const override { return true; }
  bool is_writable() const override { return true; }
  ssize_t read(char* ptr, size_t size) override {
    const std::size_t n = std::min(size, in_.size());
    std::copy_n(in_.data(), n, ptr);
    in_.remove_prefix(n);
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    out_.append(ptr, size);
    return static_cast<ssize_t>(size);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = 0;
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = 0;
  }
  socket_t socket() const override { return INVALID_SOCKET; }
  std::string take() { return std::move(out_); }

 private:
  std::string_view in_;
  std::string out_;
};

bool AnnouncesBody(const httplib::Request& req) {
  return req.has_header("Transfer-Encoding") ||
         (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0");
}

/// A Transfer-Encoding other than chunked alone (gzip, say): cpp-httplib reads such a body until
/// the read timeout and then answers 400; RFC 9112 (section 6.1) asks for 501 at once.
bool UnknownTransferCoding(const httplib::Request& req) {
  if (!req.has_header("Transfer-Encoding")) return false;
  // Two of them ("chunked", then "gzip") name a coding besides chunked: refused as one would be.
  if (req.get_header_value_count("Transfer-Encoding") > 1) return true;
  return Lower(Trim(req.get_header_value("Transfer-Encoding"))) != "chunked";
}

/// A Content-Encoding other than gzip, deflate or identity alone: cpp-httplib decompresses gzip
/// and deflate bodies, failed a brotli one as a broken body (400), and passed any other coding
/// (zstd, say) to the route undecoded, as if it were the content. It compares the name exactly,
/// so "GZIP" is one it passes on undecoded too.
bool UnknownContentCoding(const httplib::Request& req) {
  if (!req.has_header("Content-Encoding")) return false;
  if (req.get_header_value_count("Content-Encoding") > 1) return true;
  const std::string coding = req.get_header_value("Content-Encoding");
  const std::string_view name = Trim(coding);
  return name != "gzip" && name != "deflate" && Lower(name) != "identity";
}

bool AmbiguousLength(const httplib::Request& req) {
  const std::size_t lengths = req.get_header_value_count("Content-Length");
  return lengths > 1 || (lengths == 1 && req.has_header("Transfer-Encoding"));
}

/// A request that may carry a body but declares neither a length nor chunked coding has none
/// (RFC 9112, section 6.3).
bool HasNoBody(const httplib::Request& req) {
  return (req.method == "POST" || req.method == "PUT" || req.method == "PATCH" ||
          req.method == "DELETE") &&
         !req.has_header("Content-Length") && !req.has_header("Transfer-Encoding");
}

/// cpp-httplib refuses a method it does not parse with a bare 400 before any route is chosen,
/// after filling in the request's method; RFC 9110 makes that 501, and the problem names it.
/// Only for a request line of three parts ending in an HTTP version (cpp-httplib fills in the
/// version only then): "hello" or an SSH banner stays a 400.
bool UnknownMethod(const httplib::Request& req) {
  static constexpr std::array<std::string_view, 10> kParsed = {
      "GET", "HEAD", "POST", "PUT", "DELETE", "CONNECT", "OPTIONS", "TRACE", "PATCH", "PRI"};
  return !req.method.empty() && req.version.rfind("HTTP/", 0) == 0 &&
         std::find(kParsed.begin(), kParsed.end(), req.method) == kParsed.end();
}

/// The multipart Content-Type as cpp-httplib 0.11.4 looks for it, or nothing when `value` is not
/// multipart/form-data. It matches "multipart/form-data" and "boundary=" case-sensitively, where
/// media types and parameter names are case-insensitive (RFC 9110, 8.3.1): "Multipart/Form-Data;
/// Boundary=x" becomes "multipart/form-data; boundary=x" (the boundary's value is left as sent).
/// It also takes all that follows "boundary=" as the boundary, so the boundary is put last.
std::optional<std::string> MultipartContentType(std::string_view value) {
  if (MediaType(value) != "multipart/form-data") return std::nullopt;
  std::size_t semicolon = value.find(';');
  std::string out = "multipart/form-data";
  std::string boundary;  // last: cpp-httplib takes all that follows "boundary=" as the boundary
  while (semicolon != std::string_view::npos) {
    value.remove_prefix(semicolon + 1);
    semicolon = value.find(';');
    const std::string_view parameter = Trim(value.substr(0, semicolon));
    if (parameter.empty()) continue;
    const std::size_t equals = parameter.find('=');
    std::string name = Lower(Trim(parameter.substr(0, equals)));
    std::string written = "; " + name;
    if (equals != std::string_view::npos) {
      written += '=';
      written += Trim(parameter.substr(equals + 1));
    }
    if (name == "boundary") {
      boundary = std::move(written);
    } else {
      out += written;
    }
  }
  return out + boundary;
}

/// A request-line word (a method, a version) as a problem quotes it: printable ASCII, at most 40
/// characters.
std::string Quoted(const std::string& method) {
  std::string out;
  for (const char c : method.substr(0, 40)) out += (c > ' ' && c < 127) ? c : '?';
  return "'" + out + (method.size() > 40 ? "…'" : "'");
}

/// A request line of an HTTP version this server does not speak ("GET / HTTP/2.0"): cpp-httplib
/// refuses it with a bare 400; RFC 9110 (section 15.6.6) makes that 505, which says why.
bool UnsupportedVersion(const httplib::Request& req) {
  return req.version.rfind("HTTP/", 0) == 0 && req.version != "HTTP/1.1" &&
         req.version != "HTTP/1.0";
}

/// What a problem cpp-httplib answered before any route was chosen says: the limit or the rule
/// the request broke, not the status's title again.
std::string PreRoutingDetail(int status) {
  switch (status) {
    case 400:
      // Its request line, or a header line, or the blank line that ends the head: cpp-httplib
      // does not say which it could not read.
      return "the request's head could not be read: a request line such as GET /livez HTTP/1.1, "
             "then header lines, each ended by CRLF, then an empty line";
    case 414:
      return "the request target (path and query) is longer than " +
             std::to_string(CPPHTTPLIB_REQUEST_URI_MAX_LENGTH) +
             " bytes, the most this server reads";
    case 416:
      return "the Range header could not be read; this server sends every answer whole, so send "
             "the request without Range";
    default:
      return std::string(StatusTitle(status));
  }
}

/// Sets Connection: close once (a second header line besides the one already set contradicts
/// nothing but reads as a fault).
void CloseAfterAnswer(httplib::Response& res) {
  if (res.get_header_value("Connection") != "close") res.set_header("Connection", "close");
}

}  // namespace

struct HttpServer::Impl {
  std::shared_ptr<const Api> api;
  ServerOptions options;
  Server server;
  std::mutex pool_mutex;
  WorkerPool* pool = nullptr;  ///< cpp-httplib's, from listening until its shutdown; pool_mutex
  /// Connections between requests. Declared after `server`, so it ends first.
  std::unique_ptr<IdleConnections> idle;

  /// A parked connection whose next request arrived goes back to a worker; one that comes back
  /// while the pool shuts down is closed.
  void resume(int fd, std::size_t requests_left) {
    const std::lock_guard lock(pool_mutex);
    if (pool == nullptr) {
      ::shutdown(fd, SHUT_RDWR);
      ::close(fd);
      return;
    }
    pool->enqueue([this, fd, requests_left] { server.serveConnection(fd, requests_left); });
  }
  std::atomic<int> listen_fd{-1};
  /// Set by stop(): answers from then on close their connection.
  std::atomic<bool> stopping{false};
  int port = 0;
  std::thread thread;

  HttpResponse tooLarge() const { return BodyTooLargeResponse(api->options().max_body_bytes); }

  /// Expect: 100-continue is answered before routing: admit the request first, so a refusal
  /// (no token, a replica's write, a body over the limit) is sent instead of "100 Continue" and
  /// the client never sends its body.
  int expectContinue(const httplib::Request& req, httplib::Response& res) {
    if (preRoute(req, res) == httplib::Server::HandlerResponse::Handled) {
      // cpp-httplib writes this answer without the Content-Length it gives routed ones, so its
      // body ended only when the connection closed. (A refusal that leaves a body unread has
      // asked to close the connection already.)
      res.set_header("Content-Length", std::to_string(res.body.size()));
      return res.status;
    }
    t_state.admitted_before_continue = true;
    return 100;
  }

  httplib::Server::HandlerResponse preRoute(const httplib::Request& req, httplib::Response& res) {
    if (t_state.admitted_before_continue) {
      // Admitted by expectContinue for this very request (t_state is reset before each one).
      t_state.admitted_before_continue = false;
      return httplib::Server::HandlerResponse::Unhandled;
    }
    if (t_connection != nullptr) t_connection->headRead();
    // Timed from when its head was there to read, as an answer made before routing is.
    t_state = RequestState{
        true,
        t_connection != nullptr ? t_connection->created() : std::chrono::steady_clock::now(),
        {},
        {},
        false};
    t_state.request_id = RequestIdFrom(req.has_header("X-Request-Id")
                                           ? std::optional(req.get_header_value("X-Request-Id"))
                                           : std::nullopt);
    res.set_header("X-Request-Id", t_state.request_id);
    // cpp-httplib says "Accept-Ranges: bytes" unless told otherwise, and ranges are not served.
    res.set_header("Accept-Ranges", "none");
    // Every answer is whole: cpp-httplib 0.11.4 cut API answers to a Range with status 200, and
    // answered an unsatisfiable one without a body. Ignoring Range is allowed (RFC 9110, 14.2).
    const_cast<httplib::Request&>(req).ranges.clear();  // cpp-httplib's own object, not const
    // A server must accept the absolute form of a request's target (RFC 9112, 3.2.2), which
    // cpp-httplib keeps whole as the path: routed by the path it names.
    if (auto path = OriginFormPath(req.path)) const_cast<std::string&>(req.path) = std::move(*path);
    if (const auto type = req.headers.find("Content-Type"); type != req.headers.end()) {
      if (auto multipart = MultipartContentType(type->second)) {
        const_cast<std::string&>(type->second) = std::move(*multipart);
      }
    }
    t_state.admission = api->admit(req.method, req.path, Headers(req), t_state.request_id);
    if (const std::size_t hosts = req.get_header_value_count("Host");
        hosts > 1 || (hosts == 0 && req.version == "HTTP/1.1")) {
      // RFC 9112, section 3.2: a server answers 400 to an HTTP/1.1 request without a Host, or
      // with more than one (they were answered as if it had one).
      t_state.admission.rejection =
          ProblemResponse(400, hosts == 0 ? "an HTTP/1.1 request must carry a Host header"
                                          : "the request carries " + std::to_string(hosts) +
                                                " Host headers; it must carry one");
    }
    if (!t_state.admission.rejection && AmbiguousLength(req)) {
      // Two lengths (or a length and chunked coding) let a proxy and this server split the
      // stream into different requests: refuse, and close, whichever was meant.
      t_state.admission.rejection =
          ProblemResponse(400,
                          "the request declares its body's length twice (Content-Length "
                          "with another Content-Length or with Transfer-Encoding)");
    }
    if (!t_state.admission.rejection && UnknownTransferCoding(req)) {
      // Every Transfer-Encoding line, in order: "chunked" twice is two codings, not chunked.
      const std::size_t lines = req.get_header_value_count("Transfer-Encoding");
      std::string codings;
      for (std::size_t i = 0; i < lines; ++i) {
        codings += (i == 0 ? "" : ", ") + req.get_header_value("Transfer-Encoding", i);
      }
      t_state.admission.rejection = ProblemResponse(
          501, "the request's body is sent in " +
                   std::string(lines > 1 ? "transfer codings (" : "a transfer coding (") +
                   codings.substr(0, 100) +
                   ") this server does not read; send it with Content-Length, or with one "
                   "Transfer-Encoding: chunked");
    }
    if (!t_state.admission.rejection && AnnouncesBody(req) && UnknownContentCoding(req)) {
      HttpResponse refusal = ProblemResponse(
          415, "the request body's Content-Encoding (" +
                   req.get_header_value("Content-Encoding").substr(0, 100) +
                   ") is not one this server reads: send it as gzip or deflate (in lower case) or "
                   "uncompressed");
      refusal.headers.emplace_back("Accept-Encoding", "gzip, deflate");
      t_state.admission.rejection = std::move(refusal);
    }
    if (!t_state.admission.rejection && AnnouncesBody(req) &&
        (req.method == "GET" || req.method == "HEAD" || req.method == "OPTIONS")) {
      t_state.admission.rejection = ProblemResponse(400, req.method + " requests take no body");
    }
    if (!t_state.admission.rejection && req.method == "DELETE" &&
        req.has_header("Transfer-Encoding")) {
      // cpp-httplib reads a DELETE's body only by its Content-Length: a chunked one was left
      // in the stream and read as the next request. No DELETE route takes a body (Api::admit
      // refuses one first); this holds for one that would.
      t_state.admission.rejection =
          ProblemResponse(400, "a DELETE request takes no chunked body; send it without one");
    }
    if (!t_state.admission.rejection) {
      if (!HasNoBody(req)) return httplib::Server::HandlerResponse::Unhandled;
      // cpp-httplib 0.11.4 would read such a body until the client closes or the read timeout
      // passes: `curl -X POST` without -d waited 5 s for a 400. It has none, so answer now.
      handle(req, res);
      return httplib::Server::HandlerResponse::Handled;
    }
    Apply(*t_state.admission.rejection, res);
    // The body, if any, is left unread: close the connection after answering.
    if (AnnouncesBody(req)) leaveBodyUnread(req, res);
    return httplib::Server::HandlerResponse::Handled;
  }

  void handle(const httplib::Request& req, httplib::Response& res) {
    HttpRequest request = ToRequest(req);
    request.body = req.body;
    Apply(api->invoke(t_state.admission, std::move(request)), res);
  }

  void handleWithReader(const httplib::Request& req, httplib::Response& res,
                        const httplib::ContentReader& reader) {
    HttpRequest request = ToRequest(req);
    const std::size_t limit = api->options().max_body_bytes;
    std::size_t total = 0;
    bool too_large = false;
    const auto count = [&](std::size_t n) {
      total += n;
      too_large = too_large || total > limit;
      return !too_large;
    };
    bool ok = false;
    bool too_many_parts = false;
    // Only chunked is let this far as a transfer coding (UnknownTransferCoding).
    if (t_connection != nullptr && req.has_header("Transfer-Encoding")) {
      t_connection->expectChunkedBody();
    }
    if (req.is_multipart_form_data()) {
      ok = reader(
          [&](const httplib::MultipartFormData& part) {
            // A part's headers and boundary count toward the limit as well as its content: a
            // body of empty parts would otherwise cost a record each and never reach it.
            constexpr std::size_t kPartFraming = 64;
            if (request.parts.size() == kMaxFormParts) {
              too_many_parts = true;
              return false;
            }
            if (!count(kPartFraming + part.name.size() + part.filename.size() +
                       part.content_type.size())) {
              return false;
            }
            request.parts.push_back({part.name, part.filename, part.content_type, {}});
            return true;
          },
          [&](const char* data, std::size_t n) {
            if (!count(n) || request.parts.empty()) return false;
            request.parts.back().content.append(data, n);
            return true;
          });
    } else {
      // A photo's announced length in one allocation: reallocating the body as it arrived copied
      // it again at each doubling (memmove 0.9 → 0.5 % of the server's CPU under detect load).
      // Capped at a large photo's size: announcing more reserves no more (Api::admit has checked
      // the length against the limit, and the bytes are counted as they arrive).
      constexpr std::uint64_t kMaxReserve = std::uint64_t{8} << 20;
      const auto announced = req.get_header_value<std::uint64_t>("Content-Length");
      request.body.reserve(static_cast<std::size_t>(
          std::min({announced, kMaxReserve, static_cast<std::uint64_t>(limit)})));
      ok = reader([&](const char* data, std::size_t n) {
        if (!count(n)) return false;
        request.body.append(data, n);
        return true;
      });
    }
    if (too_many_parts) {
      Apply(ProblemResponse(413, "a multipart body may have at most " +
                                     std::to_string(kMaxFormParts) + " parts"),
            res);
      leaveBodyUnread(req, res);
      return;
    }
    if (too_large) {
      Apply(tooLarge(), res);
      leaveBodyUnread(req, res);
      return;
    }
    if (!ok && t_connection != nullptr) {
      if (const std::optional<std::string> refusal = t_connection->chunkedRefusal()) {
        // What follows the broken framing cannot be told from a next request: close, drained
        // first so that a client still sending reads the answer, not a reset.
        Apply(ProblemResponse(400, *refusal), res);
        leaveBodyUnread(req, res);
        return;
      }
    }
    if (!ok && t_connection != nullptr && t_connection->bodyLineTooLong()) {
      Apply(ProblemResponse(400,
                            "a line of the chunked body (a chunk size, with any extensions) "
                            "ran past " +
                                std::to_string(ConnectionStream::kMaxBodyLineBytes) + " bytes"),
            res);
      res.set_header("Connection", "close");
      return;
    }
    if (!ok) {
      Apply(bodyNotRead(), res);
      if (t_connection != nullptr &&
          t_connection->readEnd() == ConnectionStream::ReadEnd::kTooSlow) {
        leaveBodyUnread(req, res);  // it is still sending: drained without a worker, then closed
      } else {
        res.set_header("Connection", "close");
      }
      return;
    }
    Apply(api->invoke(t_state.admission, std::move(request)), res);
  }

  /// Answers with the rest of the request unread: the connection is closed after the answer,
  /// and drained first of as much as the client may still send of a body the server would have
  /// taken (its declared length; a chunked one's up to the body limit, at least 64 MiB so that a
  /// photo of any size a phone makes is covered), so that it reads the answer, not a reset.
  void leaveBodyUnread(const httplib::Request& req, httplib::Response& res) const {
    res.set_header("Connection", "close");
    if (t_connection == nullptr) return;
    const std::uint64_t cap =
        std::max<std::uint64_t>(std::uint64_t{64} << 20, api->options().max_body_bytes);
    // A chunked body says nothing of its length; a request that declares no body may still be
    // followed by bytes (the 64 KiB below, and at least kDrainAfterRefusedHead, cover those).
    std::uint64_t unread = req.has_header("Transfer-Encoding") ? cap : 0;
    if (req.has_header("Content-Length") && !req.has_header("Transfer-Encoding")) {
      unread = std::min(cap, req.get_header_value<std::uint64_t>("Content-Length"));
    }
    t_connection->leavesUnread(static_cast<std::size_t>(unread) + (std::size_t{64} << 10));
  }

  /// Why a request's body could not be read, as far as the connection tells: a client on a
  /// failing mobile link must be able to tell a stalled upload from a malformed one.
  HttpResponse bodyNotRead() const {
    const auto end =
        t_connection != nullptr ? t_connection->readEnd() : ConnectionStream::ReadEnd::kNone;
    switch (end) {
      case ConnectionStream::ReadEnd::kTimedOut:
        return ProblemResponse(408, "the request body stopped arriving: no byte of it came for " +
                                        std::to_string(options.read_timeout.count()) +
                                        " s (the read timeout)");
      case ConnectionStream::ReadEnd::kTooSlow: {
        const double waited = std::chrono::duration<double>(t_connection->bodyWaited()).count();
        char seconds[32];
        std::snprintf(seconds, sizeof seconds, "%.1f", waited);
        return ProblemResponse(
            408, "the request body came too slowly: " + std::to_string(t_connection->bodyBytes()) +
                     " bytes (with any chunk framing) after " + seconds +
                     " s of waiting for them, where the server waits at most " +
                     std::to_string(ConnectionStream::kBodyGraceReadTimeouts *
                                    options.read_timeout.count()) +
                     " s plus a second for every " + std::to_string(options.min_body_rate) +
                     " bytes (--min-body-rate)");
      }
      case ConnectionStream::ReadEnd::kClosed:
        return ProblemResponse(400,
                               "the request body ended early: the client stopped sending before "
                               "the body's end");
      case ConnectionStream::ReadEnd::kFailed:
      case ConnectionStream::ReadEnd::kNone:
        break;
    }
    return ProblemResponse(400,
                           "the request body could not be read as its headers describe it (a "
                           "malformed chunked or multipart body, or a failed connection)");
  }

  // Fills the body of error answers cpp-httplib makes itself (400 malformed, 413, …).
  httplib::Server::HandlerResponse onError(const httplib::Request& req, httplib::Response& res) {
    // A request cpp-httplib refused before routing (malformed, too long) still gets an id.
    // One refused after its headers were read (a Range it cannot parse) keeps the id it was sent,
    // so that a proxy's log and this one name it alike.
    if (!t_state.active) {
      t_state.request_id = RequestIdFrom(req.has_header("X-Request-Id")
                                             ? std::optional(req.get_header_value("X-Request-Id"))
                                             : std::nullopt);
      res.set_header("X-Request-Id", t_state.request_id);
    }
    if (t_connection != nullptr && HeadRefused(*t_connection)) {
      // A head refused while it was read: cpp-httplib saw a failed read (400).
      Apply(HeadRefusal(*t_connection), res);
      res.set_header("Connection", "close");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (!t_state.active) {
      // cpp-httplib answered before routing (a request line it cannot parse, 414, a Range it
      // cannot parse, 416) and would keep the connection: whatever body followed would then be
      // read as the next request, one a proxy in front never saw (a reviewer had nginx hand one
      // client's answer to another). Close it, draining what the client may still send.
      leaveBodyUnread(req, res);
    }
    if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
    if (res.status == 400 && UnknownMethod(req)) {
      res.status = 501;
      // OPTIONS is parsed, and answered 405 by every route (Allow names the methods it takes).
      Apply(ProblemResponse(501, "method " + Quoted(req.method) +
                                     " is not one this server answers (its routes answer GET, "
                                     "HEAD, POST, PUT and DELETE)"),
            res);
      // What followed the request line is unread: the connection cannot be reused.
      CloseAfterAnswer(res);
      return httplib::Server::HandlerResponse::Handled;
    }
    if (res.status == 400 && UnsupportedVersion(req)) {
      res.status = 505;
      Apply(ProblemResponse(505,
                            "this server speaks HTTP/1.1 and HTTP/1.0; the request line "
                            "named " +
                                Quoted(req.version)),
            res);
      CloseAfterAnswer(res);
      return httplib::Server::HandlerResponse::Handled;
    }
    const HttpResponse problem =
        res.status == 413 ? tooLarge() : ProblemResponse(res.status, PreRoutingDetail(res.status));
    res.set_content(problem.body, problem.content_type);
    return httplib::Server::HandlerResponse::Handled;
  }

  /// What cpp-httplib could not answer: a head over the budget while its request line was still
  /// being read. Written whole here, logged and counted as the logger would.
  void answerUnendedHead(ConnectionStream& stream) {
    const HttpResponse problem = HeadRefusal(stream);
    answerWithoutRequest(stream, StatusTitle(problem.status), problem, true,
                         std::chrono::steady_clock::now() - stream.created());
  }

  /// A head still coming Limits::head_timeout after its first bytes (IdleConnections): 408,
  /// written without waiting, on the thread that waits for every idle connection.
  void answerHeadTimeout(int fd) {
    ConnectionStream stream(fd, std::chrono::microseconds(0), std::chrono::microseconds(0), 0);
    answerWithoutRequest(
        stream, "Request Timeout",
        ProblemResponse(408, "the request line and headers did not all arrive within " +
                                 std::to_string(options.read_timeout.count()) +
                                 " s of their first byte"),
        false, options.read_timeout);
  }

  /// Writes `problem` on a connection whose request was never read whole, asking to close it, and
  /// counts and logs it as cpp-httplib's answers are, as taking `taken` (from the head's first
  /// bytes or its arrival). Without `wait`, only what the socket takes at once is written.
  void answerWithoutRequest(ConnectionStream& stream, std::string_view reason,
                            const HttpResponse& problem, bool wait,
                            std::chrono::steady_clock::duration taken) {
    const std::string id = RequestIdFrom(std::nullopt);
    const std::string answer = "HTTP/1.1 " + std::to_string(problem.status) + " " +
                               std::string(reason) + "\r\nContent-Type: " + problem.content_type +
                               "\r\nContent-Length: " + std::to_string(problem.body.size()) +
                               "\r\nConnection: close\r\nX-Content-Type-Options: nosniff"
                               "\r\nX-Request-Id: " +
                               id + "\r\n\r\n" + problem.body;
    for (std::size_t sent = 0; sent < answer.size();) {
      const ssize_t n = wait ? stream.write(answer.data() + sent, answer.size() - sent)
                             : ::send(stream.socket(), answer.data() + sent, answer.size() - sent,
                                      MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n <= 0) break;
      sent += static_cast<std::size_t>(n);
    }
    std::string client;
    int client_port = 0;
    stream.get_remote_ip_and_port(client, client_port);
    const double seconds = std::chrono::duration<double>(taken).count();
    api->metrics().observeRequest("unmatched", "other", problem.status, seconds);
    LogAccess({.request_id = id,
               .client = client,
               .proxy = "",
               .method = "",
               .path = "",
               .status = problem.status,
               .bytes = problem.body.size(),
               .seconds = seconds,
               .principal = ""});
  }

  void log(const httplib::Request& req, const httplib::Response& res) {
    if (t_connection != nullptr) {
      t_connection->answered(res.get_header_value("Connection") == "close");
    }
    // cpp-httplib answers some requests before routing (400, 414, 416, 501): timed from their
    // stream, and their client named from it, since cpp-httplib fills in remote_addr only after
    // the head parsed.
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    std::string label = "unmatched";
    if (t_state.active) {
      start = t_state.start;
      label = t_state.admission.route_label;
    } else if (t_connection != nullptr) {
      start = t_connection->created();
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::string peer = req.remote_addr;
    if (peer.empty() && t_connection != nullptr) {
      int client_port = 0;
      t_connection->get_remote_ip_and_port(peer, client_port);
    }
    TrustedProxies::Client client{peer};
    if (!options.trusted_proxies.empty()) {
      std::string forwarded_for;
      const auto [first, last] = req.headers.equal_range("X-Forwarded-For");
      for (auto it = first; it != last; ++it) {
        forwarded_for += (forwarded_for.empty() ? "" : ",") + it->second;
      }
      client = options.trusted_proxies.clientOf(peer, forwarded_for);
    }
    api->metrics().observeRequest(label, req.method, res.status, seconds);
    const std::string principal =
        t_state.admission.principal ? t_state.admission.principal->id : "";
    const Route* route = t_state.active ? t_state.admission.match.route : nullptr;
    const bool routine =
        route != nullptr &&
        std::ranges::find(route->routine_statuses, res.status) != route->routine_statuses.end();
    LogAccess({.request_id = t_state.request_id,
               .client = client.address,
               .proxy = client.forwarded ? peer : std::string(),
               .method = req.method,
               .path = req.path,
               .status = res.status,
               // A HEAD answer's body is counted by its headers but never sent.
               .bytes = req.method == "HEAD" ? 0 : res.body.size(),
               .seconds = seconds,
               .principal = principal,
               .cut_off = t_connection != nullptr && t_connection->writeFailed(),
               .routine = routine});
    t_state = RequestState{};
  }
};

HttpServer::HttpServer(std::shared_ptr<const Api> api, ServerOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->api = std::move(api);
  impl_->options = std::move(options);
  Impl* impl = impl_.get();
  httplib::Server& s = impl->server;

  IdleConnections::Limits idle_limits;
  idle_limits.max_parked =
      static_cast<std::size_t>(std::max(1, impl->options.max_idle_connections));
  idle_limits.head_budget = kMaxRequestHeadBytes;
  idle_limits.head_timeout = impl->options.read_timeout;
  idle_limits.answer_head_timeout = [impl](int fd) { impl->answerHeadTimeout(fd); };
  impl->idle = std::make_unique<IdleConnections>(
      [impl](int fd, std::size_t requests_left) { impl->resume(fd, requests_left); },
      std::move(idle_limits));
  impl->server.idle = impl->idle.get();
  impl->server.min_body_rate = impl->options.min_body_rate;
  const int threads = std::clamp(impl->options.threads, 1, 256);
  s.new_task_queue = [impl, threads] {
    auto* pool = new WorkerPool(static_cast<std::size_t>(threads), [impl] {
      {
        const std::lock_guard lock(impl->pool_mutex);
        impl->pool = nullptr;
      }
      impl->idle->closeAll();
    });
    const std::lock_guard lock(impl->pool_mutex);
    impl->pool = pool;
    return pool;
  };
  s.set_payload_max_length(impl->api->options().max_body_bytes);
  s.set_read_timeout(impl->options.read_timeout);
  s.set_write_timeout(impl->options.write_timeout);
  s.set_keep_alive_timeout(impl->options.keep_alive_timeout.count());
  s.set_keep_alive_max_count(
      static_cast<std::size_t>(std::max(1, impl->options.keep_alive_max_requests)));
  // The default socket options plus remembering the listening socket, to raise its backlog
  // after cpp-httplib's own listen(fd, 5). TCP_NODELAY: without it Nagle's algorithm holds a
  // response's last segment until the client's delayed ACK (about 40 ms), every request of a
  // reused connection. Set on the listening socket, Linux gives it to every accepted connection
  // (they are cloned from the listener), which is the only socket cpp-httplib lets us configure.
  s.set_tcp_nodelay(true);
  s.set_socket_options([impl](int fd) {
    int yes = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof yes);
    impl->listen_fd = fd;
  });
  s.set_pre_routing_handler([impl](const httplib::Request& req, httplib::Response& res) {
    return impl->preRoute(req, res);
  });
  // Runs as every answer is written. An answer sent while the server stops (a request in flight
  // at SIGTERM) closes its connection: a client that took it as kept alive would send its next
  // request into a socket about to close, and an upload is not retried by clients or proxies.
  s.set_post_routing_handler([impl](const httplib::Request& /*req*/, httplib::Response& res) {
    // Every answer is read as the type it names: a browser that sniffed a problem echoing a path,
    // or a text answer, could take it for a page. A tag or label SVG opened in a tab is a
    // document: it may run nothing and load nothing (cairo's own output needs neither).
    if (!res.has_header("X-Content-Type-Options")) {
      res.set_header("X-Content-Type-Options", "nosniff");
    }
    if (res.get_header_value("Content-Type").starts_with("image/svg+xml") &&
        !res.has_header("Content-Security-Policy")) {
      res.set_header("Content-Security-Policy",
                     "default-src 'none'; style-src 'unsafe-inline'; img-src data:");
    }
    if (impl->stopping) CloseAfterAnswer(res);
    // cpp-httplib adds Keep-Alive to an answer whose connection it keeps, which it decides before
    // a handler asks for the close (an answer said both), and adds its own "Connection: close"
    // beside one a refusal set when the request asked to close (the line came twice).
    if (res.get_header_value("Connection") == "close") {
      res.headers.erase("Keep-Alive");
      if (res.get_header_value_count("Connection") > 1) {
        res.headers.erase("Connection");
        res.set_header("Connection", "close");
      }
    }
  });
  s.set_error_handler(httplib::Server::HandlerWithResponse(
      [impl](const httplib::Request& req, httplib::Response& res) {
        return impl->onError(req, res);
      }));
  s.set_exception_handler(
      [](const httplib::Request& req, httplib::Response& res, const std::exception_ptr& thrown) {
        std::string what = "a non-standard exception";
        try {
          if (thrown) std::rethrow_exception(thrown);
        } catch (const std::exception& e) {
          what = e.what();
        } catch (...) {
        }
        LogRequestError(t_state.request_id, req.method + " " + req.path + ": " + what);
        Apply(ProblemResponse(500, "the server failed to handle this request"), res);
      });
  s.set_logger(
      [impl](const httplib::Request& req, const httplib::Response& res) { impl->log(req, res); });
  s.set_expect_100_continue_handler([impl](const httplib::Request& req, httplib::Response& res) {
    return impl->expectContinue(req, res);
  });
  impl->server.answer_unended_head = [impl](ConnectionStream& stream) {
    impl->answerUnendedHead(stream);
  };

  const auto plain = [impl](const httplib::Request& req, httplib::Response& res) {
    impl->handle(req, res);
  };
  const auto reading = [impl](const httplib::Request& req, httplib::Response& res,
                              const httplib::ContentReader& reader) {
    impl->handleWithReader(req, res, reader);
  };
  s.Get(".*", plain);
  s.Options(".*", plain);
  s.Post(".*", reading);
  s.Put(".*", reading);
  s.Patch(".*", reading);
  s.Delete(".*", reading);
}

HttpServer::~HttpServer() {
  stop();
}

bool HttpServer::bind(std::string* error) {
  const ServerOptions& o = impl_->options;
  if (o.port == 0) {
    impl_->port = impl_->server.bind_to_any_port(o.bind_address);
  } else {
    impl_->port = impl_->server.bind_to_port(o.bind_address, o.port) ? o.port : -1;
  }
  if (impl_->port <= 0) {
    impl_->port = 0;
    if (error) {
      const std::string why = o.port == 0 ? std::string() : WhyCannotListen(o.bind_address, o.port);
      *error = "cannot listen on " + o.bind_address + ":" + std::to_string(o.port) + ": " +
               (why.empty() ? "the address is in use, not this host's, or not permitted" : why);
    }
    return false;
  }
  if (impl_->listen_fd >= 0 && o.listen_backlog > 0) ::listen(impl_->listen_fd, o.listen_backlog);
  return true;
}

bool HttpServer::serve() {
  return impl_->server.listen_after_bind();
}

bool HttpServer::start(std::string* error) {
  if (!bind(error)) return false;
  impl_->thread = std::thread([this] { serve(); });
  for (int i = 0; i < 500 && !impl_->server.is_running(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!impl_->server.is_running()) {
    if (error) *error = "the server did not start";
    stop();
    return false;
  }
  return true;
}

void HttpServer::stop() {
  impl_->stopping = true;
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

bool HttpServer::running() const {
  return impl_->server.is_running();
}

int HttpServer::port() const {
  return impl_->port;
}

std::string HttpServer::answerRaw(std::string_view request) {
  MemoryStream stream(request);
  t_state = RequestState{};  // as the connection loop does before each request
  bool closed = false;
  impl_->server.process_request(stream, /*close_connection=*/true, closed, nullptr);
  return stream.take();
}

}  // namespace pintag::server

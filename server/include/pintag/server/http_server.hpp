#pragma once
// Serves an Api over HTTP/1.1 with cpp-httplib (the only file that includes httplib.h is
// http_server.cpp). Limits are set once here: body size (from ApiOptions), timeouts, worker
// threads, listen backlog.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "pintag/server/api.hpp"
#include "pintag/server/trusted_proxies.hpp"

namespace pintag::server {

struct ServerOptions {
  std::string bind_address = "127.0.0.1";  ///< "0.0.0.0" to serve every interface
  int port = 8080;                         ///< 0 picks a free port (see HttpServer::port)
  int threads = 4;                         ///< worker threads, 1 … 256
  std::chrono::seconds read_timeout{5};    ///< per read of a request (headers or body chunk)
  std::chrono::seconds write_timeout{5};   ///< per write of a response
  /// The pace a request body must keep: the server waits for its bytes at most four read
  /// timeouts plus a second for every min_body_rate bytes (a body trickled a byte per read
  /// timeout held a worker for as long as its length lasted); slower is answered 408 and the
  /// connection closed. 0: no minimum.
  std::uint64_t min_body_rate = 500;
  std::chrono::seconds keep_alive_timeout{5};
  int keep_alive_max_requests = 100;  ///< requests per connection before it is closed
  /// Connections waiting for a request at once (each an open socket, no thread); past this the
  /// one whose keep-alive wait ends first is closed.
  int max_idle_connections = 1024;
  int listen_backlog = 128;  ///< pending connections queued by the kernel
  /// Reverse proxies whose X-Forwarded-For names the client in the access log (default: none,
  /// the client is the connection's peer).
  TrustedProxies trusted_proxies;
};

class HttpServer {
 public:
  HttpServer(std::shared_ptr<const Api> api, ServerOptions options);
  ~HttpServer();  ///< stops and joins a server started with start()
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// Binds and listens; returns false and sets `error` when the address or port is unusable.
  bool bind(std::string* error);
  /// Serves on the calling thread until stop(); requires bind().
  bool serve();
  /// bind() and serve() on a background thread; returns once the port accepts connections.
  bool start(std::string* error);
  /// Stops accepting, finishes in-flight requests, joins the background thread.
  void stop();

  /// Whether serve() is accepting connections (stop() before that is a no-op in cpp-httplib, so a
  /// caller stopping from another thread waits for this first).
  bool running() const;

  /// The bound port (useful with port 0); 0 before bind().
  int port() const;

  /// Serves the raw bytes of one HTTP/1.1 request from memory, through the same parsing, limits,
  /// routing and handlers as a socket, and returns the raw bytes of the answer. No socket, no
  /// thread: for the whole-request fuzz target (fuzz/http_request_fuzzer.cpp).
  std::string answerRaw(std::string_view request);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pintag::server

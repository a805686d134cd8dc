// The HTTP side of dn preview, on civetweb (Debian's libcivetweb): serves the
// page at "/" and pushes each new frame to every page over a WebSocket at
// "/ws". A page that connects gets the newest frame and status at once.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

struct mg_context;
struct mg_connection;

namespace dn::cli {

class PreviewHttpServer {
 public:
  static constexpr int kMaxPages = 16;  // pages served at once; more wait for a free thread

  // `address` is HOST:PORT (PORT 0 picks a free one). A non-empty `token` must
  // be given as ?token=... by the page and its WebSocket. Throws
  // std::runtime_error naming the address when it cannot listen.
  PreviewHttpServer(const std::string& address, std::string token);
  ~PreviewHttpServer();
  PreviewHttpServer(const PreviewHttpServer&) = delete;
  PreviewHttpServer& operator=(const PreviewHttpServer&) = delete;

  int port() const { return port_; }
  // Sends `message` (encode_preview_frame) to every connected page and keeps
  // it for pages that connect later.
  void publish(std::shared_ptr<const std::vector<uint8_t>> message);
  // Sends a status message (encode_preview_status) to every page and keeps
  // it, after the newest frame, for pages that connect later.
  void publish_status(std::shared_ptr<const std::vector<uint8_t>> message);
  size_t pages() const;

 private:
  static int on_page(mg_connection* conn, void* self);
  static int on_ws_connect(const mg_connection* conn, void* self);
  static void on_ws_ready(mg_connection* conn, void* self);
  static int on_ws_data(mg_connection* conn, int bits, char* data, size_t len, void* self);
  static void on_ws_close(const mg_connection* conn, void* self);
  bool authorised(const mg_connection* conn) const;
  static void send(mg_connection* conn, const std::vector<uint8_t>& message);

  std::string token_;
  mg_context* ctx_ = nullptr;
  int port_ = 0;
  mutable std::mutex mutex_;
  std::set<mg_connection*> sockets_;
  std::shared_ptr<const std::vector<uint8_t>> latest_;
  std::shared_ptr<const std::vector<uint8_t>> status_;
};

}  // namespace dn::cli

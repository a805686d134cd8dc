#include "preview_http.hpp"

#include <civetweb.h>

#include <cstring>
#include <stdexcept>

#include "preview_page.hpp"

namespace dn::cli {

namespace {

// civetweb's global set-up, once per process.
void init_civetweb_once() {
  static const bool done = [] {
    mg_init_library(0);
    return true;
  }();
  (void)done;
}

// Constant-time comparison so the token cannot be guessed byte by byte.
bool same_secret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= unsigned(uint8_t(a[i]) ^ uint8_t(b[i]));
  return diff == 0;
}

}  // namespace

PreviewHttpServer::PreviewHttpServer(const std::string& address, std::string token) : token_(std::move(token)) {
  init_civetweb_once();
  // civetweb gives each open page (WebSocket) a worker thread of its own:
  // kMaxPages pages at once, one thread left for HTTP. A page that stops
  // reading holds a send for at most the request timeout.
  const std::string threads = std::to_string(kMaxPages + 1);
  const char* options[] = {"listening_ports", address.c_str(), "num_threads", threads.c_str(),
                           "request_timeout_ms", "10000", "enable_keep_alive", "yes", nullptr};
  mg_callbacks callbacks;
  std::memset(&callbacks, 0, sizeof callbacks);
  mg_init_data init{&callbacks, this, options};
  char text[256] = {};
  unsigned code = 0;
  mg_error_data error{&code, text, sizeof text};
  ctx_ = mg_start2(&init, &error);
  if (!ctx_) throw std::runtime_error("cannot serve the preview on " + address + ": " + text);
  mg_set_request_handler(ctx_, "/$", &PreviewHttpServer::on_page, this);
  mg_set_websocket_handler(ctx_, "/ws", &PreviewHttpServer::on_ws_connect, &PreviewHttpServer::on_ws_ready,
                           &PreviewHttpServer::on_ws_data, &PreviewHttpServer::on_ws_close, this);
  mg_server_port ports[4];
  if (mg_get_server_ports(ctx_, 4, ports) > 0) port_ = ports[0].port;
}

PreviewHttpServer::~PreviewHttpServer() {
  if (ctx_) mg_stop(ctx_);  // joins civetweb's threads: no callback runs after this
}

bool PreviewHttpServer::authorised(const mg_connection* conn) const {
  if (token_.empty()) return true;
  const mg_request_info* info = mg_get_request_info(conn);
  if (!info || !info->query_string) return false;
  char given[256];
  const int n = mg_get_var(info->query_string, std::strlen(info->query_string), "token", given, sizeof given);
  return n >= 0 && same_secret(std::string(given, size_t(n)), token_);
}

int PreviewHttpServer::on_page(mg_connection* conn, void* self) {
  auto* s = static_cast<PreviewHttpServer*>(self);
  if (!s->authorised(conn)) {
    mg_send_http_error(conn, 403, "%s", "dn preview: missing or wrong ?token=");
    return 403;
  }
  const std::string_view page = preview_page_html();
  mg_send_http_ok(conn, "text/html; charset=utf-8", (long long)page.size());
  mg_write(conn, page.data(), page.size());
  return 200;
}

int PreviewHttpServer::on_ws_connect(const mg_connection* conn, void* self) {
  return static_cast<PreviewHttpServer*>(self)->authorised(conn) ? 0 : 1;  // non-zero refuses
}

void PreviewHttpServer::on_ws_ready(mg_connection* conn, void* self) {
  auto* s = static_cast<PreviewHttpServer*>(self);
  std::shared_ptr<const std::vector<uint8_t>> latest, status;
  {
    std::lock_guard lock(s->mutex_);
    s->sockets_.insert(conn);
    latest = s->latest_;
    status = s->status_;
  }
  if (latest) send(conn, *latest);
  if (status) send(conn, *status);
}

int PreviewHttpServer::on_ws_data(mg_connection*, int, char*, size_t, void*) {
  return 1;  // the page sends nothing we act on; keep the connection
}

void PreviewHttpServer::on_ws_close(const mg_connection* conn, void* self) {
  auto* s = static_cast<PreviewHttpServer*>(self);
  std::lock_guard lock(s->mutex_);
  s->sockets_.erase(const_cast<mg_connection*>(conn));
}

void PreviewHttpServer::send(mg_connection* conn, const std::vector<uint8_t>& message) {
  // civetweb needs writes to one connection serialised (the ready callback and publish()).
  mg_lock_connection(conn);
  mg_websocket_write(conn, MG_WEBSOCKET_OPCODE_BINARY, reinterpret_cast<const char*>(message.data()), message.size());
  mg_unlock_connection(conn);
}

void PreviewHttpServer::publish(std::shared_ptr<const std::vector<uint8_t>> message) {
  std::lock_guard lock(mutex_);
  latest_ = message;
  // Under the lock, so a page closing meanwhile cannot be written after its close callback.
  for (mg_connection* conn : sockets_) send(conn, *message);
}

void PreviewHttpServer::publish_status(std::shared_ptr<const std::vector<uint8_t>> message) {
  std::lock_guard lock(mutex_);
  status_ = message;
  for (mg_connection* conn : sockets_) send(conn, *message);
}

size_t PreviewHttpServer::pages() const {
  std::lock_guard lock(mutex_);
  return sockets_.size();
}

}  // namespace dn::cli

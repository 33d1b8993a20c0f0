#include "daemon/viewer/viewer_server.h"

#include <civetweb.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

namespace cblox {
namespace {

// Browsers send small JSON commands; anything longer is ignored unread.
constexpr size_t kMaxBrowserMessageBytes = 4096;
// A browser's writer sends what is pending at most this often (coalescing changes).
constexpr auto kSendInterval = std::chrono::milliseconds(100);

}  // namespace

struct ViewerServer::Client {
  mg_connection* conn = nullptr;
  int id = 0;
  std::atomic<bool> closed{false};
  std::thread writer;
};

ViewerServer::ViewerServer(const ViewerConfig& config, ViewerModel* model, ExportRequest on_export)
    : config_(config), model_(model), on_export_(std::move(on_export)) {
  namespace fs = std::filesystem;
  const fs::path web(config_.resolvedWebRoot()), three(config_.three_js_dir);
  files_["/"] = {(web / "index.html").string(), "text/html; charset=utf-8"};
  files_["/index.html"] = files_["/"];
  files_["/viewer.js"] = {(web / "viewer.js").string(), "text/javascript; charset=utf-8"};
  files_["/viewer.css"] = {(web / "viewer.css").string(), "text/css; charset=utf-8"};
  files_["/three/three.min.js"] = {(three / "three.min.js").string(),
                                   "text/javascript; charset=utf-8"};
  files_["/three/OrbitControls.js"] = {
      (three / "examples" / "js" / "controls" / "OrbitControls.js").string(),
      "text/javascript; charset=utf-8"};
}

ViewerServer::~ViewerServer() { stop(); }

bool ViewerServer::start(std::string* error) {
  for (const auto& [url, file] : files_) {
    if (!std::filesystem::is_regular_file(file.first)) {
      if (error) {
        *error = "missing " + file.first + " (served as " + url +
                 "; web_root and three_js_dir in the settings; is libjs-three installed?)";
      }
      return false;
    }
  }
  mg_init_library(0);
  const std::string ports = config_.bind_address + ":" + std::to_string(config_.port);
  const std::string threads = std::to_string(config_.max_clients + 4);
  const std::string timeout =
      std::to_string(static_cast<long long>(config_.client_timeout_s * 1000.0));
  const char* options[] = {"listening_ports",
                           ports.c_str(),
                           "num_threads",
                           threads.c_str(),
                           "websocket_timeout_ms",
                           timeout.c_str(),
                           "request_timeout_ms",
                           timeout.c_str(),
                           "enable_websocket_ping_pong",
                           "yes",
                           "enable_directory_listing",
                           "no",
                           nullptr};
  mg_callbacks callbacks{};
  context_ = mg_start(&callbacks, this, options);
  if (context_ == nullptr) {
    if (error) *error = "cannot serve on " + ports + " (address in use or not available?)";
    mg_exit_library();
    return false;
  }
  mg_set_request_handler(context_, "/", &ViewerServer::onHttp, this);
  mg_set_websocket_handler(context_, "/ws", &ViewerServer::onWsConnect, &ViewerServer::onWsReady,
                           &ViewerServer::onWsData, &ViewerServer::onWsClose, this);
  return true;
}

void ViewerServer::stop() {
  if (context_ == nullptr) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [conn, client] : clients_) client->closed = true;
  }
  model_->wakeAll();
  mg_stop(context_);  // closes the connections: every close handler joins its writer
  context_ = nullptr;
  mg_exit_library();
}

ViewerServerCounters ViewerServer::counters() const {
  ViewerServerCounters c;
  c.clients_accepted = accepted_.load();
  c.clients_refused = refused_.load();
  c.clients_dropped = dropped_.load();
  c.browser_messages_ignored = ignored_.load();
  c.export_requests = exports_.load();
  c.http_not_found = not_found_.load();
  c.messages_sent = messages_.load();
  c.bytes_sent = bytes_.load();
  return c;
}

size_t ViewerServer::clients() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return clients_.size();
}

int ViewerServer::onHttp(mg_connection* conn, void* self_ptr) {
  auto* self = static_cast<ViewerServer*>(self_ptr);
  const mg_request_info* info = mg_get_request_info(conn);
  const std::string uri = info->local_uri != nullptr ? info->local_uri : "";
  if (std::strcmp(info->request_method, "GET") != 0 &&
      std::strcmp(info->request_method, "HEAD") != 0) {
    mg_send_http_error(conn, 405, "%s", "only GET");
    return 405;
  }
  const auto file = self->files_.find(uri);
  if (file != self->files_.end()) {
    mg_send_mime_file2(conn, file->second.first.c_str(), file->second.second.c_str(),
                       "X-Content-Type-Options: nosniff\r\nCache-Control: no-cache\r\n");
    return 200;
  }
  // /export/<id>.ply: a mesh the page asked the mapper for.
  const std::string prefix = "/export/", suffix = ".ply";
  if (uri.size() > prefix.size() + suffix.size() && uri.compare(0, prefix.size(), prefix) == 0 &&
      uri.compare(uri.size() - suffix.size(), suffix.size(), suffix) == 0) {
    const std::string digits = uri.substr(prefix.size(), uri.size() - prefix.size() - suffix.size());
    if (digits.size() <= 18 && digits.find_first_not_of("0123456789") == std::string::npos) {
      const std::string path = self->model_->exportFile(std::stoll(digits));
      if (!path.empty() && std::filesystem::is_regular_file(path)) {
        mg_send_mime_file2(conn, path.c_str(), "application/octet-stream",
                           "X-Content-Type-Options: nosniff\r\n"
                           "Content-Disposition: attachment; filename=\"cblox_mesh.ply\"\r\n");
        return 200;
      }
      self->not_found_.fetch_add(1, std::memory_order_relaxed);
      mg_send_http_error(conn, 404, "%s",
                         "no such export here (cblox-viewer serves a mesh the mapper wrote only "
                         "when it can read the mapper's output directory)");
      return 404;
    }
  }
  self->not_found_.fetch_add(1, std::memory_order_relaxed);
  mg_send_http_error(conn, 404, "%s", "not found");
  return 404;
}

int ViewerServer::onWsConnect(const mg_connection* conn, void* self_ptr) {
  auto* self = static_cast<ViewerServer*>(self_ptr);
  std::lock_guard<std::mutex> lock(self->mutex_);
  if (self->clients_.size() >= static_cast<size_t>(self->config_.max_clients)) {
    self->refused_.fetch_add(1, std::memory_order_relaxed);
    return 1;  // refused
  }
  self->clients_[conn] = std::make_unique<Client>();
  return 0;
}

void ViewerServer::onWsReady(mg_connection* conn, void* self_ptr) {
  auto* self = static_cast<ViewerServer*>(self_ptr);
  std::lock_guard<std::mutex> lock(self->mutex_);
  const auto it = self->clients_.find(conn);
  if (it == self->clients_.end()) return;
  Client* client = it->second.get();
  client->conn = conn;
  client->id = self->model_->addClient();
  self->accepted_.fetch_add(1, std::memory_order_relaxed);
  client->writer = std::thread([self, client] { self->writerLoop(client); });
}

void ViewerServer::writerLoop(Client* client) {
  BrowserMessage message;
  while (!client->closed.load()) {
    if (!model_->waitForWork(client->id, std::chrono::milliseconds(500))) continue;
    while (!client->closed.load() &&
           model_->nextMessage(client->id, config_.max_message_bytes, &message)) {
      const int opcode = message.binary ? MG_WEBSOCKET_OPCODE_BINARY : MG_WEBSOCKET_OPCODE_TEXT;
      const int written =
          mg_websocket_write(client->conn, opcode, message.data.data(), message.data.size());
      if (written <= 0) {
        // Closed, or not taken within client_timeout_s: the browser is dropped (it
        // reconnects and gets everything again).
        if (!client->closed.exchange(true)) dropped_.fetch_add(1, std::memory_order_relaxed);
        mg_websocket_write(client->conn, MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE, "", 0);
        break;
      }
      messages_.fetch_add(1, std::memory_order_relaxed);
      bytes_.fetch_add(message.data.size(), std::memory_order_relaxed);
    }
    std::this_thread::sleep_for(kSendInterval);
  }
}

int ViewerServer::onWsData(mg_connection* conn, int bits, char* data, size_t length,
                           void* self_ptr) {
  auto* self = static_cast<ViewerServer*>(self_ptr);
  const int opcode = bits & 0x0f;
  if (opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE) return 0;
  if (opcode == MG_WEBSOCKET_OPCODE_PING || opcode == MG_WEBSOCKET_OPCODE_PONG) return 1;
  (void)conn;
  bool is_export = false;
  if (opcode == MG_WEBSOCKET_OPCODE_TEXT && length <= kMaxBrowserMessageBytes) {
    const nlohmann::json j = nlohmann::json::parse(data, data + length, nullptr, false);
    is_export = j.is_object() && j.contains("type") && j["type"] == "export";
  }
  if (is_export && self->config_.allow_export && self->on_export_) {
    self->exports_.fetch_add(1, std::memory_order_relaxed);
    self->on_export_();
  } else {
    self->ignored_.fetch_add(1, std::memory_order_relaxed);
  }
  return 1;
}

void ViewerServer::onWsClose(const mg_connection* conn, void* self_ptr) {
  auto* self = static_cast<ViewerServer*>(self_ptr);
  std::unique_ptr<Client> client;
  {
    std::lock_guard<std::mutex> lock(self->mutex_);
    const auto it = self->clients_.find(conn);
    if (it == self->clients_.end()) return;
    client = std::move(it->second);
    self->clients_.erase(it);
  }
  client->closed = true;
  self->model_->wakeAll();
  if (client->writer.joinable()) client->writer.join();
  if (client->id != 0) self->model_->removeClient(client->id);
}

}  // namespace cblox

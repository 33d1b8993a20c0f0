#pragma once

// cblox-viewer's web server (civetweb): the page's files and three.js from fixed paths only,
// the WebSocket /ws that streams the ViewerModel to each browser from a writer thread of its
// own, and /export/<id>.ply for meshes the page asked the mapper for.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "daemon/viewer/viewer_config.h"
#include "daemon/viewer/viewer_model.h"

struct mg_context;
struct mg_connection;

namespace cblox {

/// Counters of the web server since start. Plain value type.
struct ViewerServerCounters {
  uint64_t clients_accepted = 0;
  uint64_t clients_refused = 0;    ///< max_clients were connected
  uint64_t clients_dropped = 0;    ///< a send failed or timed out (client_timeout_s)
  uint64_t browser_messages_ignored = 0;  ///< anything a browser sends but an allowed export
  uint64_t export_requests = 0;
  uint64_t http_not_found = 0;
  uint64_t messages_sent = 0;
  uint64_t bytes_sent = 0;
};

/// Thread-safety: start() and stop() from one thread; counters() from any. The callbacks of
/// civetweb run on its threads; each browser's messages are written by a thread of its own.
class ViewerServer {
 public:
  /// Called (on a civetweb thread) when a browser asks for an export and allow_export is set.
  using ExportRequest = std::function<void()>;
  /// `config` and `model` must outlive the server.
  ViewerServer(const ViewerConfig& config, ViewerModel* model, ExportRequest on_export);
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  /// Binds bind_address:port and starts serving; false with a message when it cannot (the
  /// port is taken, the page's files are missing).
  bool start(std::string* error);
  /// Closes every connection and stops. Idempotent.
  void stop();
  ViewerServerCounters counters() const;
  size_t clients() const;

 private:
  struct Client;
  static int onHttp(mg_connection* conn, void* self);
  static int onWsConnect(const mg_connection* conn, void* self);
  static void onWsReady(mg_connection* conn, void* self);
  static int onWsData(mg_connection* conn, int bits, char* data, size_t length, void* self);
  static void onWsClose(const mg_connection* conn, void* self);
  void writerLoop(Client* client);

  const ViewerConfig& config_;
  ViewerModel* const model_;
  const ExportRequest on_export_;
  mg_context* context_ = nullptr;
  std::map<std::string, std::pair<std::string, std::string>> files_;  // url -> (path, mime)

  mutable std::mutex mutex_;  // guards clients_
  std::map<const mg_connection*, std::unique_ptr<Client>> clients_;

  std::atomic<uint64_t> accepted_{0}, refused_{0}, dropped_{0}, ignored_{0}, exports_{0},
      not_found_{0}, messages_{0}, bytes_{0};
};

}  // namespace cblox

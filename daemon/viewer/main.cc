// cblox-viewer: watch the map live in a browser. Subscribes the mapper's mesh stream
// (CBLOX_MESH_UPDATE, CBLOX_SUBVOLUMES), the vehicle's poses (CBLOX_FRAME_POSE, or
// CBLOX_GT_POSE without a tracker), keyframes (CBLOX_KEYFRAME, CBLOX_KEYFRAME_POSES), the map
// status, every process's heartbeat and the planner's local grid, and serves a page
// (three.js) that shows them, with a WebSocket stream to each browser.
//
//   cblox-viewer                                   # http://127.0.0.1:8090/
//   cblox-viewer --config /etc/cblox/viewer.yaml --port 8091
//
// Asks the mapper for a mesh refresh (command mesh_refresh on CBLOX_CMD) at start and after a
// lost message; with allow_export, the page's Export button sends export_mesh and offers the
// PLY (the viewer must be able to read the mapper's output directory).
// Publishes: CBLOX_HEARTBEAT every status_period_s, CBLOX_CMD (mesh_refresh, export_mesh).
// Listens on bind_address:port, 127.0.0.1:8090 by default (this computer only).
// Exit status: 0 stopped by SIGINT/SIGTERM, 1 runtime error (the port cannot be bound), 2
// usage or configuration error.

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "daemon/common/daemon_options.h"
#include "daemon/common/heartbeat.h"
#include "daemon/common/run_loop.h"
#include "daemon/common/systemd_notify.h"
#include "daemon/viewer/viewer_config.h"
#include "daemon/viewer/viewer_lcm_node.h"
#include "daemon/viewer/viewer_model.h"
#include "daemon/viewer/viewer_server.h"

namespace cblox {
namespace {

struct Args {
  DaemonOptions daemon;
  std::optional<int> port;
  std::optional<std::string> bind, web_root, up;
  bool allow_export = false;
};

int run(const Args& args) {
  ViewerConfig config = loadDaemonConfig<ViewerConfig>(args.daemon, loadViewerConfig);
  if (args.port) config.port = *args.port;
  if (args.bind) config.bind_address = *args.bind;
  if (args.web_root) config.web_root = *args.web_root;
  if (args.allow_export) config.allow_export = true;
  if (args.up) config.up_axis = *args.up;
  if (const std::string e = config.validate(); !e.empty()) throw ConfigError(e);

  lcm::LCM lcm(config.lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-viewer: cannot open LCM (url '%s')\n", config.lcm_url.c_str());
    return 1;
  }
  ViewerModel model({config.max_trajectory_points, config.up_axis, config.allow_export});
  ViewerLcmNode node(config, &lcm, &model);
  node.subscribe();
  ViewerServer server(config, &model, [&node] { node.requestExport(); });
  std::string error;
  if (!server.start(&error)) {
    std::fprintf(stderr, "cblox-viewer: %s\n", error.c_str());
    return 1;
  }
  installStopHandlers();
  if (!args.daemon.quiet) {
    std::printf("viewer: http://%s:%d/ (%s; up axis %s)\n", config.bind_address.c_str(),
                config.port, config.allow_export ? "export allowed" : "read-only",
                config.up_axis.c_str());
    std::fflush(stdout);
  }

  const auto heartbeat = [&](const char* state) {
    HeartbeatBuilder hb("cblox-viewer", state);
    const ViewerServerCounters s = server.counters();
    hb.add("clients", static_cast<uint64_t>(server.clients()))
        .add("clients_accepted", s.clients_accepted)
        .add("clients_refused", s.clients_refused)
        .add("clients_dropped", s.clients_dropped)
        .add("browser_messages_ignored", s.browser_messages_ignored)
        .add("export_requests", s.export_requests)
        .add("http_not_found", s.http_not_found)
        .add("browser_messages_sent", s.messages_sent)
        .add("browser_bytes_sent", s.bytes_sent);
    node.addTo(&hb);
    const heartbeat_t msg = hb.build();
    lcm.publish(config.heartbeat_channel, &msg);
  };
  SystemdNotifier notifier;
  const std::vector<PeriodicTask> tasks{
      {config.status_period_s, 0.0, [&] { heartbeat("running"); }},
      {0.5, 0.2, [&] { node.tick(); }},
  };
  const int exit_code = serveUntilStopped(lcm, "cblox-viewer", tasks, &notifier);
  server.stop();
  heartbeat("stopped");
  return exit_code;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::Args args;
  CLI::App app{
      "cblox-viewer: watch the map live in a browser: the mapper's mesh, subvolumes,\n"
      "trajectory, keyframes, loop closures, fusions, the distance field near the vehicle\n"
      "and every process's health. Runs until SIGINT/SIGTERM.\n"
      "Exit status: 0 stopped by signal, 1 runtime error, 2 usage/configuration error.",
      "cblox-viewer"};
  cblox::addDaemonOptions(app, &args.daemon, "config/viewer.yaml");
  app.add_option("--port", args.port, "TCP port (over the settings' port)")->type_name("PORT");
  app.add_option("--bind", args.bind,
                 "address to listen on (over bind_address; default 127.0.0.1: this computer\n"
                 "only; 0.0.0.0 lets anyone who reaches this computer watch)")
      ->type_name("ADDR");
  app.add_option("--web-root", args.web_root, "the page's files (over web_root)")
      ->type_name("DIR");
  app.add_option("--up", args.up,
                 "the up axis of the map's frame (over up_axis): z for ground-truth poses, -y\n"
                 "for the tracker's (its frame is its first camera's, y down)")
      ->type_name("AXIS");
  app.add_flag("--allow-export", args.allow_export,
               "the page's Export button asks the mapper for a mesh (over allow_export)");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  return cblox::runProcess("cblox-viewer", [&] { return cblox::run(args); });
}

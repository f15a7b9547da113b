// dashboard: a live web page of the rigs on a DDS domain, for a browser on the same machine.
// It speaks only the DDS topics (clients/dashboard/rig_feed.h) and serves one self-contained
// page (HTML, CSS and JavaScript in this binary: no fetch leaves the machine, so it works on a
// lab PC without internet) plus a small JSON API the page polls:
//
//   GET  /                                  the page
//   GET  /api/rigs                          the rigs seen, and whether DDS is open
//   GET  /api/state?rig=ID&since=SEQ        one rig's newest values and history since SEQ
//   POST /api/shadow?rig=ID&action=A&arg=X  a shadow model command (effect_on, effect_off, set,
//                                           reset, fit_now); answers with its command_id
//   GET  /api/health                        DDS open or not, samples, CPU (does not count as
//                                           watching: a monitor does not keep DDS open)
//
// Writes (any method but GET and HEAD) are taken only from the dashboard's own page: the Origin
// (or Referer) must name this dashboard and the X-Mpdrig-Token header carry the token the page
// was served with; else 403 (clients/dashboard/write_guard.h). The connections are bounded:
// request size, deadlines, open connections (clients/dashboard/guarded_server.h).
#include <signal.h>
#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include <httplib.h>
#include <CLI/CLI.hpp>

#include "clients/dashboard/api_json.h"
#include "clients/dashboard/guarded_server.h"
#include "clients/dashboard/page.h"
#include "clients/dashboard/rig_feed.h"
#include "clients/dashboard/write_guard.h"

namespace {

using mpdrig::dashboard::CommandSentJson;
using mpdrig::dashboard::ErrorJson;
using mpdrig::dashboard::HealthJson;

struct Args {
  int domain = 0;
  int port = 8080;
  std::string host = "127.0.0.1";
  std::vector<std::string> rigs;
  std::string shadow_id = "shadow";
  std::vector<std::string> allow_hosts;  // more names of this machine a write may come from
  std::string dds_config;
  std::string security;  // make-class's OUT/NAME; empty: no DDS Security
  double idle_s = 5.0;
  double frame_hz = 20.0;
  double duration_s = 0.0;
};

double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// The page with this process's write token in it (page.html's placeholder).
std::string PageWithToken(const std::string& token) {
  std::string page = mpdrig::dashboard::PageHtml();
  const std::string placeholder = "{{MPDRIG_TOKEN}}";
  const std::size_t at = page.find(placeholder);
  if (at == std::string::npos) {
    std::fprintf(stderr, "dashboard: the page has no token placeholder (page.html)\n");
    std::abort();
  }
  return page.replace(at, placeholder.size(), token);
}

void Route(httplib::Server* server, mpdrig::dashboard::RigFeed* feed,
           const mpdrig::dashboard::WriteGuard* guard) {
  server->set_default_headers({{"Cache-Control", "no-store"}});
  // Every write passes the guard before it is routed, and before its body is asked for
  // ("Expect: 100-continue": a refused write's body is never sent).
  auto refused = [guard](const httplib::Request& req, httplib::Response& res) {
    if (req.method == "GET" || req.method == "HEAD") return false;
    const mpdrig::Status allowed = guard->Check(req);
    if (allowed.ok()) return false;
    res.status = 403;
    res.set_content(ErrorJson(allowed.message()), "application/json");
    return true;
  };
  server->set_pre_routing_handler([refused](const httplib::Request& req, httplib::Response& res) {
    return refused(req, res) ? httplib::Server::HandlerResponse::Handled
                             : httplib::Server::HandlerResponse::Unhandled;
  });
  server->set_expect_100_continue_handler(
      [refused](const httplib::Request& req, httplib::Response& res) {
        return refused(req, res) ? 403 : 100;
      });
  server->Get(
      "/", [page = PageWithToken(guard->token())](const httplib::Request&, httplib::Response& res) {
        res.set_content(page, "text/html; charset=utf-8");
      });
  server->Get("/api/rigs", [feed](const httplib::Request&, httplib::Response& res) {
    feed->Touch();
    res.set_content(feed->RigsJson(), "application/json");
  });
  server->Get("/api/state", [feed](const httplib::Request& req, httplib::Response& res) {
    feed->Touch();
    std::uint64_t since = 0;
    if (req.has_param("since"))
      since = std::strtoull(req.get_param_value("since").c_str(), nullptr, 10);
    res.set_content(feed->StateJson(req.get_param_value("rig"), since), "application/json");
  });
  server->Post("/api/shadow", [feed](const httplib::Request& req, httplib::Response& res) {
    auto sent = feed->SendShadowCommand(req.get_param_value("rig"), req.get_param_value("action"),
                                        req.get_param_value("arg"));
    if (!sent.ok()) {
      res.status = 400;
      res.set_content(ErrorJson(sent.status().message()), "application/json");
      return;
    }
    res.set_content(CommandSentJson(*sent), "application/json");
  });
  server->Get("/api/health", [feed](const httplib::Request&, httplib::Response& res) {
    res.set_content(HealthJson(feed->Health(), CpuSeconds()), "application/json");
  });
}

// Stops the server on SIGINT or SIGTERM, or after `duration_s` (0: never). The signals are
// blocked in every thread and taken here with sigtimedwait, so no handler runs in a signal
// context.
void StopOnSignal(httplib::Server* server, const sigset_t& signals, double duration_s) {
  timespec step{0, 200'000'000};
  double waited_s = 0.0;
  for (;;) {
    if (sigtimedwait(&signals, nullptr, &step) > 0) break;
    waited_s += 0.2;
    if (duration_s > 0.0 && waited_s >= duration_s) break;
    if (!server->is_running() && waited_s > 5.0) return;  // it failed to listen
  }
  server->stop();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("dashboard - a live web page of the rigs and the shadow model on a DDS domain");
  app.footer(
      "Serves http://HOST:PORT/ (a browser on this machine: http://127.0.0.1:8080/). The page\n"
      "shows the pressure along the pipe (rig, observer estimate, shadow model), PT1 with the\n"
      "observer's BHP estimate and the shadow's, piston, choke and pump, the rig's status, and\n"
      "the shadow's error with a switch per catalogue effect and a \"fit now\" button.\n"
      "DDS is opened only while a browser watches (a request in the last --idle-s seconds):\n"
      "with no browser the rigs' services send nothing to the dashboard.\n"
      "  mpdrig serve --rig rig-1 &  mpdrig shadow --rig rig-1 &  dashboard --port 8080");
  Args args;
  app.add_option("--domain", args.domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  app.add_option("--port", args.port, "TCP port of the page (0: any free port, printed)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  app.add_option("--host", args.host,
                 "address to listen on (127.0.0.1: this machine only; 0.0.0.0: the lab's network)")
      ->capture_default_str();
  app.add_option("--rig", args.rigs, "a rig to show (repeatable; default: every rig seen)");
  app.add_option("--shadow", args.shadow_id,
                 "which shadow of each rig to show and command (`mpdrig shadow --shadow-id`)")
      ->capture_default_str();
  app.add_option("--allow-host", args.allow_hosts,
                 "another name of this machine the page may be opened by, for writes (repeatable; "
                 "127.0.0.1, localhost, --host and the host name are always allowed)");
  app.add_option("--dds-config", args.dds_config,
                 "Cyclone DDS configuration: a file or inline XML (default: loopback only)");
  app.add_option("--security", args.security,
                 "DDS Security: an identity directory of a class (deploy/security/make-class OUT "
                 "NAME: OUT/NAME) allowed to read the rig given with --rig (one); its topics, and "
                 "its shadow's, are then in partition rig.<rig id>. Refuses an invalid directory, "
                 "saying why");
  app.add_option("--idle-s", args.idle_s, "close DDS this long after the last request [s]")
      ->check(CLI::Range(0.5, 3600.0))
      ->capture_default_str();
  app.add_option("--frame-hz", args.frame_hz,
                 "how often the topics are drained and a chart point is kept [Hz]")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  app.add_option("--duration", args.duration_s, "stop after this long [s] (0: until Ctrl-C)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  if (!args.dds_config.empty() && args.dds_config.front() != '<') {
    std::FILE* f = std::fopen(args.dds_config.c_str(), "rb");
    if (f == nullptr) {
      std::fprintf(stderr, "dashboard: cannot read --dds-config %s\n", args.dds_config.c_str());
      return 2;
    }
    std::string text;
    char buffer[4096];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) text.append(buffer, n);
    std::fclose(f);
    args.dds_config = text;
  }

  // Block the stop signals before any thread starts, so that only StopOnSignal takes them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  mpdrig::dashboard::FeedOptions options;
  options.domain = args.domain;
  options.dds_config = args.dds_config;
  options.rigs = args.rigs;
  options.shadow_id = args.shadow_id;
  options.security_dir = args.security;
  options.idle_s = args.idle_s;
  options.frame_hz = args.frame_hz;
  auto feed = mpdrig::dashboard::RigFeed::Create(options);
  if (!feed.ok()) {
    std::fprintf(stderr, "dashboard: %s\n", feed.status().message().c_str());
    return 1;
  }
  mpdrig::dashboard::GuardedServer server{mpdrig::dashboard::ServerLimits{}};
  const int port = server.Bind(args.host, args.port);
  if (port <= 0) {
    std::fprintf(stderr, "dashboard: cannot listen on %s:%d (in use? try another --port)\n",
                 args.host.c_str(), args.port);
    return 1;
  }
  std::vector<std::string> hosts = args.allow_hosts;
  hosts.push_back(args.host);
  const mpdrig::dashboard::WriteGuard guard(hosts, port);
  Route(&server, feed->get(), &guard);
  std::printf("dashboard: http://%s:%d/ (DDS domain %d)\n", args.host.c_str(), port, args.domain);
  std::fflush(stdout);
  std::thread stopper(StopOnSignal, &server, signals, args.duration_s);
  const bool listened = server.listen_after_bind();
  stopper.join();
  server.StopConnections();
  return listened ? 0 : 1;
}

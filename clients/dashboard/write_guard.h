// Who may write through the dashboard. A write (POST /api/shadow switches an effect or a wave
// speed in a shadow model others watch) must come from the dashboard's own page, not from any
// other page open in the same browser: a browser sends a cross-site "simple" POST (text/plain,
// no custom header) without asking, and before this guard such a POST set the shadow's wave
// speed. A write is taken only with both:
//   - an Origin header (or, without one, a Referer) naming this dashboard: http://HOST:PORT with
//     PORT the dashboard's and HOST one of its own names (127.0.0.1, localhost, [::1], --host,
//     the address the request came in on, this machine's host name, --allow-host);
//   - the header X-Mpdrig-Token carrying this process's token: 128 random bits drawn at start
//     and written into the page the dashboard serves. Another site can neither read the page
//     (the browser's same-origin policy) nor send a custom header cross-site without a CORS
//     preflight, which the dashboard never grants.
// Anything else is refused with 403 and the reason.
#pragma once

#include <string>
#include <vector>

#include <httplib.h>

#include "model/common/status.h"

namespace mpdrig::dashboard {

inline constexpr char kTokenHeader[] = "X-Mpdrig-Token";

class WriteGuard {
 public:
  // `hosts`: names this dashboard is reached by, beyond the loopback names, the address the
  // request came in on and the machine's host name; `port`: the port it listens on.
  WriteGuard(std::vector<std::string> hosts, int port);

  // The token the page sends (hex).
  const std::string& token() const { return token_; }

  // Ok, or why the write is refused.
  Status Check(const httplib::Request& request) const;

 private:
  bool IsOwnOrigin(const std::string& origin, const std::string& local_addr) const;

  std::vector<std::string> hosts_;  // lower case; IPv6 in brackets
  int port_;
  std::string token_;
};

}  // namespace mpdrig::dashboard

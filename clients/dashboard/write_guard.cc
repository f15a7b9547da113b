#include "clients/dashboard/write_guard.h"

#include <sys/random.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>

namespace mpdrig::dashboard {

namespace {

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::string RandomToken() {
  unsigned char bytes[16];
  std::size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t n = getrandom(bytes + got, sizeof bytes - got, 0);
    if (n <= 0) {
      std::perror("dashboard: getrandom");
      std::abort();  // no token, no writes: never run with a guessable one
    }
    got += static_cast<std::size_t>(n);
  }
  static const char kHex[] = "0123456789abcdef";
  std::string token;
  for (unsigned char b : bytes) {
    token += kHex[b >> 4];
    token += kHex[b & 15];
  }
  return token;
}

// A comparison whose time does not tell how much of the token was right.
bool SameToken(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differ |= static_cast<unsigned char>(a[i] ^ b[i]);
  return differ == 0;
}

// "http://host:port/anything" -> host (lower case, IPv6 in brackets) and port (80 if none);
// false for any other scheme or a malformed authority.
bool SplitOrigin(const std::string& origin, std::string* host, int* port) {
  const std::string scheme = "http://";
  if (Lower(origin.substr(0, scheme.size())) != scheme) return false;
  std::string authority = origin.substr(scheme.size());
  authority = authority.substr(0, authority.find_first_of("/?#"));
  if (authority.empty() || authority.find('@') != std::string::npos) return false;
  std::string port_text;
  if (authority.front() == '[') {
    const std::size_t close = authority.find(']');
    if (close == std::string::npos) return false;
    *host = authority.substr(0, close + 1);
    const std::string rest = authority.substr(close + 1);
    if (!rest.empty()) {
      if (rest.front() != ':') return false;
      port_text = rest.substr(1);
    }
  } else {
    const std::size_t colon = authority.find(':');
    *host = authority.substr(0, colon);
    if (colon != std::string::npos) port_text = authority.substr(colon + 1);
  }
  *host = Lower(*host);
  if (port_text.empty()) {
    *port = 80;
    return !host->empty();
  }
  if (port_text.size() > 5 || port_text.find_first_not_of("0123456789") != std::string::npos)
    return false;
  *port = std::atoi(port_text.c_str());
  return !host->empty();
}

}  // namespace

WriteGuard::WriteGuard(std::vector<std::string> hosts, int port)
    : port_(port), token_(RandomToken()) {
  hosts_ = {"127.0.0.1", "localhost", "[::1]"};
  char name[256] = "";
  if (gethostname(name, sizeof name - 1) == 0 && name[0] != '\0') hosts.push_back(name);
  for (std::string& host : hosts) {
    host = Lower(host);
    if (host.empty() || host == "0.0.0.0" || host == "::" || host == "[::]") continue;
    if (host.find(':') != std::string::npos && host.front() != '[') host = "[" + host + "]";
    if (std::find(hosts_.begin(), hosts_.end(), host) == hosts_.end()) hosts_.push_back(host);
  }
}

bool WriteGuard::IsOwnOrigin(const std::string& origin, const std::string& local_addr) const {
  std::string host;
  int port = 0;
  if (!SplitOrigin(origin, &host, &port) || port != port_) return false;
  if (std::find(hosts_.begin(), hosts_.end(), host) != hosts_.end()) return true;
  // The address this request came in on (with --host 0.0.0.0, the lab network's address).
  std::string local = Lower(local_addr);
  if (local.find(':') != std::string::npos) local = "[" + local + "]";
  return !local.empty() && host == local;
}

Status WriteGuard::Check(const httplib::Request& request) const {
  const std::string self = "http://127.0.0.1:" + std::to_string(port_);
  std::string origin = request.get_header_value("Origin");
  std::string which = "Origin";
  if (origin.empty()) {
    origin = request.get_header_value("Referer");
    which = "Referer";
  }
  if (origin.empty())
    return Status::Error("refused: a write must come from the dashboard's own page (" + self +
                         "/), and this request has neither an Origin nor a Referer header");
  if (!IsOwnOrigin(origin, request.local_addr))
    return Status::Error("refused: a write from another site (" + which + " " +
                         origin.substr(0, 200) +
                         ") is not allowed; only the dashboard's own page (" + self +
                         "/ or another of its names) may write");
  if (!SameToken(request.get_header_value(kTokenHeader), token_))
    return Status::Error(std::string("refused: a write needs the ") + kTokenHeader +
                         " header of this dashboard's page (missing or wrong: reload the page)");
  return Status::Ok();
}

}  // namespace mpdrig::dashboard

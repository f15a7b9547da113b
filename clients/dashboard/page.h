// The dashboard's page: one self-contained HTML document (CSS and JavaScript inline, charts drawn
// on canvases), generated at build time from clients/dashboard/page.html.
#pragma once

#include <string>

namespace mpdrig::dashboard {

const std::string& PageHtml();

}  // namespace mpdrig::dashboard

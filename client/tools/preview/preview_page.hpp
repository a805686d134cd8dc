// The preview page (preview/page.html, embedded at build time).
#pragma once

#include <string_view>

namespace dn::cli {

std::string_view preview_page_html();

}  // namespace dn::cli

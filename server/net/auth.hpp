// Authentication: shared-token comparison and Unix peer credentials.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

namespace dn::server::net {

// Compares in time that depends only on the length of `expected`, so the
// position of the first differing byte does not leak through timing.
bool tokens_equal(std::string_view expected, std::string_view presented);

// Unix-domain peers must run as our own uid, root, or one of `allowed`.
// Returns false (and the peer uid) when the peer is not allowed or cannot be identified.
bool unix_peer_allowed(int fd, const std::vector<uint32_t>& allowed, uint32_t& peer_uid);

}  // namespace dn::server::net

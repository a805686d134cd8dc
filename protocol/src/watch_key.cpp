// The shape of a watch key (1.6): the decoder's rule, shared with senders
// that want to check a key before encoding it.
#include "dn/protocol/messages.hpp"

namespace dn::protocol {

bool is_well_formed_watch_key(std::string_view key) {
  if (key.empty()) return true;
  if (key.size() != kWatchKeyLength) return false;
  for (char ch : key)
    if (!((ch >= '0' && ch <= '9') || (ch >= 'a' && ch <= 'f'))) return false;
  return true;
}

}  // namespace dn::protocol

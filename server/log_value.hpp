// How a log field's string value is written: logfmt, quoted when needed, with
// every character that could end a line, forge one, reorder what a reader
// sees or drive a terminal escaped. Client-supplied strings (names, fields a
// peer sent) go through here, so no peer can write a line of its own.
#pragma once

#include <string>
#include <string_view>

namespace dn::log {

// Appends v to out as one logfmt value. Escaped (inside quotes):
//  - ASCII controls and DEL: \n, \r, \t, else \xHH;
//  - C1 controls U+0080..U+009F (NEL, CSI ...), the line and paragraph
//    separators U+2028/U+2029, and the bidirectional marks, embeddings,
//    overrides and isolates (U+061C, U+200E/F, U+202A..U+202E, U+2066..U+2069):
//    \u{XXXX};
//  - bytes that are not well-formed UTF-8 (a lone 0x85 or 0x9B is NEL or CSI
//    to a Latin-1 reader): \xHH.
// Everything else, including other non-ASCII text, is copied as is.
void append_value(std::string& out, std::string_view v);

}  // namespace dn::log

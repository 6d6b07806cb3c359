#pragma once
/// @file
/// Internal helper: base64 encoding and decoding (RFC 4648 alphabet) as used by VTK XML files.
/// Not part of the public API.

#include <optional>
#include <string>
#include <string_view>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::internal {

/// Base64 encoding of `bytes`, padded with '='.
std::string EncodeBase64(std::string_view bytes);

/// Decodes base64 `text`, ignoring whitespace. Padding ('=') may also occur in the middle, at a
/// 4-character boundary, as when VTK encodes a header and its data separately and concatenates
/// them: the decoded pieces are concatenated. Returns nullopt on an invalid character or a
/// dangling single character; `bad_at` then receives its index in `text`.
std::optional<std::string> DecodeBase64(std::string_view text, std::size_t* bad_at = nullptr);

}  // namespace gipsi::internal
GIPSI_EXPORT_END

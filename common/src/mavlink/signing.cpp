#include "uavsim/common/mavlink/signing.hpp"

#include <algorithm>

#include "uavsim/common/mavlink/sha256.hpp"

namespace uavsim::common::mavlink {

SignatureBytes compute_signature(const SecretKey& key, std::span<const std::uint8_t> signed_part) {
  Sha256 hasher;
  hasher.update(key);
  hasher.update(signed_part);
  const Sha256Digest digest = hasher.finish();
  SignatureBytes sig;
  std::copy_n(digest.begin(), sig.size(), sig.begin());
  return sig;
}

}  // namespace uavsim::common::mavlink

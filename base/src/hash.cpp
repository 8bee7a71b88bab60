#include "geoanchor/base/hash.hpp"

#include <openssl/evp.h>

#include <array>
#include <cstring>
#include <fstream>
#include <memory>

#include "geoanchor/base/error.hpp"

namespace geoanchor {
namespace {

struct MdCtxDeleter {
  void operator()(EVP_MD_CTX* c) const { EVP_MD_CTX_free(c); }
};
using MdCtx = std::unique_ptr<EVP_MD_CTX, MdCtxDeleter>;

std::string to_hex(const unsigned char* d, unsigned n) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * n);
  for (unsigned i = 0; i < n; ++i) {
    out += kHex[d[i] >> 4];
    out += kHex[d[i] & 0xF];
  }
  return out;
}

class Sha256 {
 public:
  Sha256() : ctx_(EVP_MD_CTX_new()) { EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr); }
  void update(const void* p, std::size_t n) { EVP_DigestUpdate(ctx_.get(), p, n); }
  std::string hex() {
    std::array<unsigned char, EVP_MAX_MD_SIZE> d{};
    unsigned n = 0;
    EVP_DigestFinal_ex(ctx_.get(), d.data(), &n);
    return to_hex(d.data(), n);
  }

 private:
  MdCtx ctx_;
};

}  // namespace

std::string sha256_hex(std::string_view bytes) {
  Sha256 h;
  h.update(bytes.data(), bytes.size());
  return h.hex();
}

std::string sha256_file_hex(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open for hashing: " + std::strerror(errno));
  Sha256 h;
  std::array<char, 1 << 16> buf{};
  while (in) {
    in.read(buf.data(), buf.size());
    h.update(buf.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw Error(ErrorKind::io, "E_READ", path.string() + ": read error while hashing");
  return h.hex();
}

std::string FileHashCache::sha256_hex(const std::filesystem::path& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  const auto time = ec ? std::filesystem::file_time_type{} : std::filesystem::last_write_time(path, ec);
  if (ec) return sha256_file_hex(path);  // names the failure
  const std::string absolute = std::filesystem::absolute(path, ec).string();
  if (ec || absolute.empty()) return sha256_file_hex(path);  // no key to keep it under
  Key key{absolute, size, time};
  {
    const std::lock_guard lock(mutex_);
    if (const auto it = hashes_.find(key); it != hashes_.end()) return it->second;
  }
  std::string hex = sha256_file_hex(path);  // outside the lock: two threads may both read a new file once
  const std::lock_guard lock(mutex_);
  return hashes_.emplace(std::move(key), std::move(hex)).first->second;
}

}  // namespace geoanchor

// SHA-256 (FIPS 180-4), for recording exactly which renders and ground truth a result was made from.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace weathergs {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, size_t size);
  void update(const std::string& s) { update(s.data(), s.size()); }
  std::string hex_digest();  // finalizes; the object must not be updated afterwards

 private:
  void block(const uint8_t* p);
  uint32_t h_[8];
  uint8_t buffer_[64];
  size_t buffered_ = 0;
  uint64_t length_ = 0;
};

std::string sha256_hex(const std::string& bytes);
std::string sha256_file(const std::string& path);  // InputError if unreadable

}  // namespace weathergs

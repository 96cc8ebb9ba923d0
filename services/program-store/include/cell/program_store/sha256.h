// A small, dependency-free SHA-256 (FIPS 180-4) for program content hashes.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace cell::program_store {

class Sha256 {
 public:
  Sha256();
  void Update(std::string_view bytes);
  void Update(const void* data, std::size_t size);
  // Finishes the hash; the object must not be updated afterwards.
  std::array<std::uint8_t, 32> Digest();
  // Finishes the hash and returns it as 64 lower-case hex digits.
  std::string HexDigest();

 private:
  void Block(const std::uint8_t* p);

  std::array<std::uint32_t, 8> h_;
  std::array<std::uint8_t, 64> buffer_{};
  std::size_t buffered_ = 0;
  std::uint64_t length_ = 0;  // bytes
  bool finished_ = false;
};

// SHA-256 of `bytes` as 64 lower-case hex digits.
std::string Sha256Hex(std::string_view bytes);

}  // namespace cell::program_store

// A listing's pages (DESIGN §6 `--limit N`, `--after CURSOR`): a service answers one page of rows in the
// listing's order (jobs by id, programs and records by name) within its reply's bound, and says whether rows
// are left; a client asks page after page. One helper for each side, so every listing pages the same way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

namespace cell::records {

// The bound of a listing reply's text (`string<65536> info` in the IDL).
inline constexpr std::size_t kReplyBytes = 65536;

// The service side: rows are added in order until Add refuses one, because the page holds `limit` rows (0: no
// limit but the bound) or the row would not fit in `max_bytes`. The refused row and those after it are left
// for the next page: the page shrinks to fit rather than fail.
class PageBuilder {
 public:
  explicit PageBuilder(std::uint32_t limit, std::size_t max_bytes = kReplyBytes);
  bool Add(const nlohmann::json& row);  // false: refused, stop (more() is then true)
  std::size_t rows() const { return rows_; }
  bool more() const { return more_; }
  std::string Text() const { return text_ + "]"; }  // the bare JSON array

 private:
  std::uint32_t limit_;
  std::size_t max_bytes_, rows_ = 0;
  bool more_ = false;
  std::string text_ = "[";
};

// One page as a service answered it.
struct Page {
  nlohmann::json rows = nlohmann::json::array();
  bool more = false;
};

// The client side: pages from after `after` (exclusive; "" from the first) until `limit` rows (0: all) or the
// end. `fetch(after, want)` asks for one page of at most `want` rows (0: as many as fit); the next page
// starts after the last row's `key` ("id" or "name"; a number is sent in decimal). Throws cell::Error
// kInternal when a service says rows are left but sends none (it would loop forever).
using FetchPage = std::function<Page(const std::string& after, std::uint32_t want)>;
nlohmann::json CollectPages(std::uint32_t limit, std::string after, const std::string& key,
                            const FetchPage& fetch);

}  // namespace cell::records

#include "cell/records/page.h"

#include "cell/error/error.h"

namespace cell::records {

PageBuilder::PageBuilder(std::uint32_t limit, std::size_t max_bytes) : limit_(limit), max_bytes_(max_bytes) {}

bool PageBuilder::Add(const nlohmann::json& row) {
  if (more_) return false;
  if (limit_ != 0 && rows_ == limit_) {
    more_ = true;
    return false;
  }
  const std::string text = row.dump();
  // The separator before it and the closing bracket must fit too.
  if (text_.size() + (rows_ ? 1 : 0) + text.size() + 1 > max_bytes_) {
    // Rows are bounded far below a reply: one that fills a page alone is a bug, not a big listing.
    if (rows_ == 0) throw Error(Errc::kInternal, "a listing row larger than a reply");
    more_ = true;
    return false;
  }
  if (rows_) text_ += ',';
  text_ += text;
  ++rows_;
  return true;
}

nlohmann::json CollectPages(std::uint32_t limit, std::string after, const std::string& key,
                            const FetchPage& fetch) {
  nlohmann::json all = nlohmann::json::array();
  while (limit == 0 || all.size() < limit) {
    Page page = fetch(after, limit == 0 ? 0 : limit - static_cast<std::uint32_t>(all.size()));
    if (!page.rows.is_array()) throw Error(Errc::kInternal, "a listing page that is not an array");
    if (page.rows.empty()) {
      if (page.more) throw Error(Errc::kInternal, "a listing page without rows says more are left");
      break;
    }
    const nlohmann::json& last = page.rows.back()[key];
    after = last.is_string() ? last.get<std::string>() : last.dump();
    for (auto& r : page.rows) all.push_back(std::move(r));
    if (!page.more) break;
  }
  // A service that ignores the limit still yields no more rows than asked.
  if (limit != 0 && all.size() > limit) all.erase(all.begin() + limit, all.end());
  return all;
}

}  // namespace cell::records

// `cellctl watch`: the page's state (CellView::Snapshot) as a terminal frame: stations in MTConnect
// vocabulary, alarms, backlog bars, pallets that wait and why, the newest jobs. Plain text, optionally
// coloured with ANSI escapes; fits `width` columns.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace cell::dashboard {

struct TextStyle {
  int width = 100;
  bool color = false;
  int jobs = 10;  // newest jobs shown
};

std::string RenderText(const nlohmann::json& snapshot, const TextStyle& style);

}  // namespace cell::dashboard

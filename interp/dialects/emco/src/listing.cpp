// The manual's listing style -> tape format (see listing.h).
#include "listing.h"

#include <vector>

#include "cell/interp/scan.h"

namespace cell::interp::emco {

namespace {

bool IsLetter(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}

char Up(char c) {
  return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
}

// One word of a listing block as a tape word ("" when it is a placeholder): w has no blanks and starts with
// its letter.
std::string Word(const std::string& w) {
  bool only_dots = true;
  for (std::size_t i = IsLetter(w[0]) ? 1 : 0; i < w.size(); ++i) only_dots = only_dots && w[i] == '.';
  if (only_dots) return {};  // "F.....", "N.....", "....."
  if (!IsLetter(w[0])) return w;
  char letter = Up(w[0]);
  std::string out(1, letter);
  std::size_t i = 1;
  if (letter == 'P' || letter == 'D') {
    if (i < w.size() && scan::IsDigit(w[i])) out += w[i++];
    if (i < w.size() && w[i] == '=') ++i;
    out += '=';
  } else if (i < w.size() && w[i] == '=') {
    ++i;  // "K=00,000"
  }
  std::string value = w.substr(i);
  if (letter == 'D') {
    // "2.000" / "2,000": the German thousands separator.
    std::string v;
    for (std::size_t k = 0; k < value.size(); ++k) {
      char c = value[k];
      bool sep = (c == '.' || c == ',') && value.size() - k - 1 == 3 && scan::AllDigits(value.substr(k + 1));
      if (!sep) v += c;
    }
    value = v;
  } else {
    for (char& c : value) {
      if (c == ',') c = '.';
    }
  }
  return out + value;
}

// The words of a "/"-separated piece: blanks go ("F 120", "Z + 10,000"), each letter starts a word.
void Piece(std::string_view piece, std::string& out) {
  std::string flat;
  for (char c : piece) {
    if (c != ' ' && c != '\t') flat += c;
  }
  std::size_t i = 0;
  while (i < flat.size()) {
    std::size_t j = i + 1;
    while (j < flat.size() && !IsLetter(flat[j])) ++j;
    std::string w = Word(flat.substr(i, j - i));
    if (!w.empty()) {
      if (!out.empty()) out += ' ';
      out += w;
    }
    i = j;
  }
}

std::string Block(std::string_view line) {
  std::string out;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= line.size(); ++i) {
    char c = i < line.size() ? line[i] : '/';
    if (c == '(') {  // a comment goes through as it is
      Piece(line.substr(start, i - start), out);
      std::size_t close = line.find(')', i);
      std::size_t end = close == std::string_view::npos ? line.size() : close + 1;
      if (!out.empty()) out += ' ';
      out += line.substr(i, end - i);
      i = end - 1;
      start = end;
      continue;
    }
    if (c != '/') continue;
    Piece(line.substr(start, i - start), out);
    start = i + 1;
  }
  return out;
}

std::string Header(std::string_view t) {
  if (t[0] == '%') return std::string(t);
  std::string out = "O";
  for (char c : t.substr(1)) {
    if (c != ' ' && c != '\t') out += c;
  }
  return out;
}

}  // namespace

std::string ImportListing(std::string_view text) {
  std::vector<std::string_view> lines = scan::Lines(text);
  std::vector<std::string> out(lines.size());
  int last_block = -1;  // the output line the current block is written to
  bool open = false;    // that block's line ended with "/"
  for (std::size_t n = 0; n < lines.size(); ++n) {
    std::string_view raw = lines[n];
    std::string_view t = scan::Trim(raw);
    if (t.empty()) continue;  // the manual's listings put blank lines inside blocks (ln 3249-3251)
    char first = Up(t[0]);
    bool starts_blank = raw[0] == ' ' || raw[0] == '\t';
    bool new_block = first == 'N' || first == '%' || first == 'O' || first == '(';
    if (!new_block && last_block >= 0 && (open || starts_blank)) {
      std::string more = Block(t);
      if (!more.empty()) out[last_block] += (out[last_block].empty() ? "" : " ") + more;
    } else if ((first == 'O' || first == '%') && t.size() > 1 && t.find('/') == std::string_view::npos) {
      out[n] = Header(t);
      last_block = -1;
    } else {
      out[n] = Block(t);
      last_block = static_cast<int>(n);
    }
    open = t.back() == '/';
  }
  std::string joined;
  for (const std::string& l : out) {
    joined += l;
    joined += '\n';
  }
  return joined;
}

}  // namespace cell::interp::emco

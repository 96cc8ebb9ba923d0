// Runs every case of tests/conformance/<dialect> through the real cell-interp binary (the dialect is
// CELL_CONFORMANCE_DIALECT; one CTest test per dialect corpus, <dialect>_conformance).
//
// A case is NAME.<dialect> (the program, e.g. NAME.ktapl, NAME.okuma) plus NAME.expected (the canonical JSON
// lines, derived by hand from the manual) and, for the negative corpus, NAME.diag (the exact diagnostic line;
// exit status 1). Optional inputs: NAME.params (--params), NAME.tools (--tools), NAME.lib/ (--lib),
// NAME.probe (--probe-model), NAME.args (more options on one line, e.g. --listing).
// JSON objects must have the same keys; numbers compare to 1e-3, everything else exactly.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string Env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

std::string Dialect() {
  std::string d = Env("CELL_CONFORMANCE_DIALECT");
  return d.empty() ? "ktapl" : d;
}

fs::path CorpusDir() {
  return fs::path(Env("CELL_SOURCE_DIR")) / "tests" / "conformance" / Dialect();
}

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string l;
  while (std::getline(in, l)) {
    if (!l.empty() && l.back() == '\r') l.pop_back();
    if (!l.empty()) out.push_back(l);
  }
  return out;
}

bool Same(const nlohmann::json& a, const nlohmann::json& b, std::string& why, const std::string& path) {
  if (a.is_number() && b.is_number()) {
    if (std::fabs(a.get<double>() - b.get<double>()) <= 1e-3) return true;
    why = path + ": " + a.dump() + " != " + b.dump();
    return false;
  }
  if (a.type() != b.type()) {
    why = path + ": " + a.dump() + " != " + b.dump();
    return false;
  }
  if (a.is_object()) {
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (!b.contains(it.key())) {
        why = path + "." + it.key() + " missing in actual";
        return false;
      }
      if (!Same(it.value(), b[it.key()], why, path + "." + it.key())) return false;
    }
    for (auto it = b.begin(); it != b.end(); ++it) {
      if (!a.contains(it.key())) {
        why = path + "." + it.key() + " not expected";
        return false;
      }
    }
    return true;
  }
  if (a.is_array()) {
    if (a.size() != b.size()) {
      why = path + ": array size";
      return false;
    }
    for (size_t i = 0; i < a.size(); ++i) {
      if (!Same(a[i], b[i], why, path + "[" + std::to_string(i) + "]")) return false;
    }
    return true;
  }
  if (a != b) {
    why = path + ": " + a.dump() + " != " + b.dump();
    return false;
  }
  return true;
}

std::vector<std::string> Cases() {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(CorpusDir(), ec)) {
    if (e.path().extension() == "." + Dialect()) out.push_back(e.path().stem().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

class Corpus : public ::testing::TestWithParam<std::string> {};

// The shell command that runs case `name` with its inputs, in the corpus folder, up to the program's name.
std::string CaseCommand(const std::string& name) {
  const fs::path dir = CorpusDir();
  std::string cmd =
      "cd '" + dir.string() + "' && '" + Env("CELL_BIN_DIR") + "/cell-interp' --dialect " + Dialect();
  if (fs::exists(dir / (name + ".args"))) {
    auto args = Lines(Slurp(dir / (name + ".args")));
    if (!args.empty()) cmd += " " + args[0];
  }
  if (fs::exists(dir / (name + ".params"))) cmd += " --params " + name + ".params";
  if (fs::exists(dir / (name + ".tools"))) cmd += " --tools " + name + ".tools";
  if (fs::exists(dir / (name + ".lib"))) cmd += " --lib " + name + ".lib";
  if (fs::exists(dir / (name + ".probe"))) cmd += " --probe-model " + name + ".probe";
  return cmd;
}

TEST_P(Corpus, MatchesHandDerivedExpectation) {
  const std::string name = GetParam();
  const fs::path dir = CorpusDir();
  ASSERT_TRUE(fs::exists(dir / (name + ".expected"))) << name << ": no .expected file";
  std::string cmd = CaseCommand(name);
  fs::path err =
      fs::temp_directory_path() / (Dialect() + "_conf_" + name + "_" + std::to_string(::getpid()) + ".err");
  cmd += " '" + name + "." + Dialect() + "' 2>'" + err.string() + "'";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  int status = ::pclose(p);
  int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::string stderr_text = Slurp(err);
  fs::remove(err);

  bool negative = fs::exists(dir / (name + ".diag"));
  EXPECT_EQ(code, negative ? 1 : 0) << name << " stderr: " << stderr_text;
  if (negative) {
    auto want = Lines(Slurp(dir / (name + ".diag")));
    auto got = Lines(stderr_text);
    EXPECT_EQ(got, want) << name;
  } else {
    EXPECT_EQ(stderr_text, "") << name;
  }
  auto want = Lines(Slurp(dir / (name + ".expected")));
  auto got = Lines(out);
  for (size_t i = 0; i < std::max(want.size(), got.size()); ++i) {
    if (i >= want.size()) {
      ADD_FAILURE() << name << ": unexpected extra op " << got[i];
      break;
    }
    if (i >= got.size()) {
      ADD_FAILURE() << name << ": missing op " << want[i];
      break;
    }
    nlohmann::json w = nlohmann::json::parse(want[i], nullptr, false);
    nlohmann::json g = nlohmann::json::parse(got[i], nullptr, false);
    ASSERT_FALSE(w.is_discarded()) << name << ".expected line " << i + 1 << " is not JSON";
    ASSERT_FALSE(g.is_discarded()) << name << ": output line " << i + 1 << " is not JSON: " << got[i];
    std::string why;
    if (!Same(w, g, why, "")) {
      ADD_FAILURE() << name << " op " << i + 1 << ": " << why << "\n  expected " << want[i] << "\n  actual   "
                    << got[i];
      break;
    }
  }
}

TEST(CorpusSize, HasCases) {
  EXPECT_GE(Cases().size(), 10u) << CorpusDir();
}

// DESIGN §4: exit 2 on a usage error or a dialect that is not implemented yet (one-line message).
int RunCli(const std::string& args, std::string* err_text) {
  fs::path err = fs::temp_directory_path() / ("conf_cli_" + std::to_string(::getpid()) + ".err");
  std::string cmd =
      "'" + Env("CELL_BIN_DIR") + "/cell-interp' " + args + " >/dev/null 2>'" + err.string() + "'";
  int status = std::system(cmd.c_str());
  if (err_text) *err_text = Slurp(err);
  fs::remove(err);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A dialect without a corpus here is not implemented yet.
TEST(CellInterpCli, UnimplementedDialectsExitTwoWithOneLine) {
  for (const char* d : {"okuma", "emco", "balt"}) {
    if (fs::exists(CorpusDir().parent_path() / d)) continue;
    std::string err;
    EXPECT_EQ(RunCli(std::string("--dialect ") + d + " x.nc", &err), 2) << d;
    EXPECT_EQ(Lines(err).size(), 1u) << err;
  }
}

TEST(CellInterpCli, UsageErrorsExitTwo) {
  EXPECT_EQ(RunCli("", nullptr), 2);
  EXPECT_EQ(RunCli("--dialect ktapl", nullptr), 2);
  EXPECT_EQ(RunCli("--dialect fanuc x.nc", nullptr), 2);
  EXPECT_EQ(RunCli("--dialect ktapl --bogus x.nc", nullptr), 2);
  EXPECT_EQ(RunCli("--dialect ktapl /nonexistent/program.nc", nullptr), 2);
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// cell-interp --svg (docs/plot.md) on one corpus program of the dialect: every motion op of the hand-derived
// expectation but the first (it only says where the path starts) is one path element of its kind in each view
// (a lathe's half-section; a machining centre's plan and elevation), and xmllint reads the page.
TEST(CellInterpSvg, PlotsACorpusProgram) {
  const std::map<std::string, std::pair<std::string, int>> kCase = {
      {"ktapl", {"p2_9_01_bolt_hole_circle", 2}},
      {"okuma", {"p8_lap_copy_turning_g86", 1}},
      {"emco", {"e57_thread_hands", 1}},
      {"balt", {"gtl_example_4", 2}}};
  const auto it = kCase.find(Dialect());
  ASSERT_NE(it, kCase.end()) << "no plot case for " << Dialect();
  const auto& [name, views] = it->second;
  const fs::path svg =
      fs::temp_directory_path() / (Dialect() + "_plot_" + std::to_string(::getpid()) + ".svg");
  const std::string cmd =
      CaseCommand(name) + " --svg '" + svg.string() + "' '" + name + "." + Dialect() + "' >/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const std::string page = Slurp(svg);
  std::map<std::string, int> ops;
  bool first = true;
  for (const auto& line : Lines(Slurp(CorpusDir() / (name + ".expected")))) {
    const std::string op = nlohmann::json::parse(line).value("op", "");
    const std::map<std::string, std::string> kClass = {
        {"rapid", "rapid"}, {"linear", "feed"}, {"arc", "arc"}, {"thread", "thread"}, {"probe", "probe"}};
    if (!kClass.count(op)) continue;
    if (!first) ++ops[kClass.at(op)];
    first = false;
  }
  ASSERT_FALSE(ops.empty());
  for (const char* kind : {"rapid", "feed", "arc", "thread", "probe"})
    EXPECT_EQ(Count(page, std::string("<path class=\"") + kind + "\""), views * ops[kind]) << kind;
  EXPECT_EQ(Count(page, "<g class=\"view\""), views);
  EXPECT_EQ(page.find("<script"), std::string::npos);
  EXPECT_EQ(std::system(("xmllint --noout --nonet '" + svg.string() + "'").c_str()), 0);
  fs::remove(svg);
}

// The coverage table of docs/dialects/<dialect>.md (one section headed "## Coverage ...", header row
// `| Element | Manual ln | Status | Corpus |`): every row names the manual's lines, says yes / refused /
// issue N, and its corpus column names cases that exist and show it (a yes row a case with .expected, a
// refused row one with .diag). Each breach names the doc line, the element and the rule.
struct CaseFiles {
  std::string name;
  bool expected = false;
  bool diag = false;
};

std::vector<CaseFiles> CaseFileList() {
  std::vector<CaseFiles> out;
  for (const auto& name : Cases()) {
    out.push_back(
        {name, fs::exists(CorpusDir() / (name + ".expected")), fs::exists(CorpusDir() / (name + ".diag"))});
  }
  return out;
}

std::string Trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

// "| a | b |" -> {"a", "b"}.
std::vector<std::string> Cells(const std::string& row) {
  std::vector<std::string> out;
  std::string t = Trim(row);
  if (t.size() < 2 || t.front() != '|' || t.back() != '|') return out;
  std::string cell;
  for (size_t i = 1; i < t.size(); ++i) {
    if (t[i] == '|') {
      out.push_back(Trim(cell));
      cell.clear();
    } else {
      cell += t[i];
    }
  }
  return out;
}

bool IsDigit(char c) {
  return c >= '0' && c <= '9';
}

// Digits, ranges `1539-1545` and comma lists of them.
bool ValidLines(const std::string& s) {
  size_t i = 0;
  auto number = [&] {
    size_t b = i;
    while (i < s.size() && IsDigit(s[i])) ++i;
    return i > b;
  };
  auto blanks = [&] {
    while (i < s.size() && s[i] == ' ') ++i;
  };
  for (;;) {
    if (!number()) return false;
    if (i < s.size() && s[i] == '-') {
      ++i;
      if (!number()) return false;
    }
    blanks();
    if (i == s.size()) return true;
    if (s[i] != ',') return false;
    ++i;
    blanks();
  }
}

// "" when the status is allowed; else the rule it breaks.
std::string StatusRule(const std::string& status, std::string& word) {
  size_t i = 0;
  while (i < status.size() && std::isalpha(static_cast<unsigned char>(status[i]))) ++i;
  word = status.substr(0, i);
  if (i < status.size() && IsDigit(status[i])) word.clear();
  if (word == "yes" || word == "refused") return "";
  if (word != "issue") return "status must start with yes, refused or issue N (found '" + status + "')";
  size_t j = i;
  while (j < status.size() && status[j] == ' ') ++j;
  size_t k = j;
  while (k < status.size() && IsDigit(status[k])) ++k;
  if (k == j || k == i) return "status 'issue' must be followed by an issue number";
  std::string rest = Trim(status.substr(k));
  if (rest.size() < 2) return "status 'issue N' must say whether the cell refuses it today";
  return "";
}

// Case references of the Corpus column: tokens of [A-Za-z0-9_*] that contain '_'.
std::vector<std::string> CaseRefs(const std::string& corpus) {
  std::vector<std::string> out;
  std::string tok;
  auto flush = [&] {
    if (tok.find('_') != std::string::npos) out.push_back(tok);
    tok.clear();
  };
  for (char c : corpus) {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '*') {
      tok += c;
    } else {
      flush();
    }
  }
  flush();
  return out;
}

bool RefMatches(const std::string& ref, const std::string& name) {
  if (!ref.empty() && ref.back() == '*') return name.rfind(ref.substr(0, ref.size() - 1), 0) == 0;
  return name == ref || name.rfind(ref + "_", 0) == 0;
}

// The failures of one row ("" cells already split); `where` names it in each message.
std::vector<std::string> RowFailures(const std::vector<std::string>& c, const std::vector<CaseFiles>& cases,
                                     const std::string& where) {
  std::vector<std::string> out;
  if (c.size() != 4) return {where + ": a row must have 4 cells, has " + std::to_string(c.size())};
  if (c[0].empty()) out.push_back(where + ": Element is empty");
  if (!ValidLines(c[1])) out.push_back(where + ": Manual ln must be line numbers (found '" + c[1] + "')");
  std::string word;
  std::string rule = StatusRule(c[2], word);
  if (!rule.empty()) out.push_back(where + ": " + rule);
  if (c[3].find("no case") != std::string::npos)
    out.push_back(where + ": 'no case' is not allowed: write the case and name it");
  bool has_expected = false;
  bool has_diag = false;
  for (const auto& ref : CaseRefs(c[3])) {
    bool any = false;
    for (const auto& k : cases) {
      if (!RefMatches(ref, k.name)) continue;
      any = true;
      has_expected = has_expected || k.expected;
      has_diag = has_diag || k.diag;
    }
    if (!any) out.push_back(where + ": corpus reference '" + ref + "' matches no case in " + Dialect());
  }
  if (word == "yes" && !has_expected)
    out.push_back(where + ": a yes row must reference a case with a .expected (a run that shows it)");
  if (word == "refused" && !has_diag)
    out.push_back(where + ": a refused row must reference a case with a .diag (the alarm)");
  return out;
}

// Checks the coverage section of `doc`; returns the failures and counts the rows checked.
std::vector<std::string> CoverageFailures(const std::string& doc_name, const std::string& doc,
                                          const std::vector<CaseFiles>& cases, size_t& rows) {
  const std::string header = "| Element | Manual ln | Status | Corpus |";
  std::vector<std::string> out;
  std::istringstream in(doc);
  std::string l;
  int line = 0, sections = 0;
  bool in_section = false, in_table = false, header_seen = false;
  rows = 0;
  while (std::getline(in, l)) {
    ++line;
    if (l.rfind("## ", 0) == 0) {
      in_section = l.rfind("## Coverage", 0) == 0;
      sections += in_section ? 1 : 0;
      in_table = false;
      continue;
    }
    if (!in_section) continue;
    if (Trim(l) == header) {
      header_seen = in_table = true;
      continue;
    }
    if (!in_table) continue;
    if (Trim(l).rfind('|', 0) != 0) {
      in_table = false;
      continue;
    }
    auto c = Cells(l);
    if (!c.empty() && c[0].find_first_not_of("-: ") == std::string::npos) continue;  // |---|---|
    ++rows;
    std::string where = doc_name + ":" + std::to_string(line) + " row '" + (c.empty() ? "" : c[0]) + "'";
    for (auto& f : RowFailures(c, cases, where)) out.push_back(f);
  }
  if (sections != 1) out.push_back(doc_name + ": needs exactly one section headed '## Coverage'");
  if (!header_seen) out.push_back(doc_name + ": no coverage table with the header " + header);
  if (header_seen && rows == 0) out.push_back(doc_name + ": the coverage table is empty");
  return out;
}

TEST(Coverage, TableRowsNameTheManualAndExistingCases) {
  fs::path doc = fs::path(Env("CELL_SOURCE_DIR")) / "docs" / "dialects" / (Dialect() + ".md");
  ASSERT_TRUE(fs::exists(doc)) << doc;
  size_t rows = 0;
  auto failures = CoverageFailures("docs/dialects/" + Dialect() + ".md", Slurp(doc), CaseFileList(), rows);
  std::cout << "[ coverage ] " << Dialect() << ": " << rows << " rows checked, " << failures.size()
            << " failures\n";
  for (const auto& f : failures) ADD_FAILURE() << f;
}

INSTANTIATE_TEST_SUITE_P(Dialect, Corpus, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string s = info.param;
                           for (char& c : s) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return s;
                         });

}  // namespace

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
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
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

INSTANTIATE_TEST_SUITE_P(Dialect, Corpus, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string s = info.param;
                           for (char& c : s) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return s;
                         });

}  // namespace

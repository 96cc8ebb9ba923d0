// `cell-oracle-gen parts`: one part in every dialect of its kind (issue 33 item 3, docs/testing.md "Parts").
// Each part's programs run through cell-interp; their finished contours must agree with the first program's.
#include <unistd.h>

#include <algorithm>
#include <iostream>

#include "cell/oracle/oracle.h"
#include "run.h"

namespace fs = std::filesystem;

namespace cell::oracle {
namespace {

struct PartOptions {
  std::string dir = "tests/oracle/parts", only, interp = "cell-interp";
  bool plant = false, verbose = false;
};

bool ParsePartArgs(int argc, char** argv, PartOptions& o) {
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--dir")
      o.dir = value();
    else if (a == "--part")
      o.only = value();
    else if (a == "--interp")
      o.interp = value();
    else if (a == "--plant")
      o.plant = true;
    else if (a == "--verbose")
      o.verbose = true;
    else
      return false;
  }
  return true;
}

// Runs one program; its contour, or why there is none.
std::optional<Contour> RunProgram(const PartOptions& o, const fs::path& dir, const PartProgram& p,
                                  const fs::path& tmp, std::string* why) {
  const Module* mod = FindModule(p.dialect);
  if (!mod) return *why = "no dialect " + p.dialect, std::nullopt;
  std::string args = " --dialect " + p.dialect;
  if (!p.params.empty()) args += " --params " + Quote((dir / p.params).string());
  if (!p.tools.empty()) args += " --tools " + Quote((dir / p.tools).string());
  fs::path out = tmp / "cell.out", err = tmp / "cell.err";
  int rc = Shell(Quote(o.interp) + args + " " + Quote((dir / p.file).string()) + " >" + Quote(out.string()) +
                 " 2>" + Quote(err.string()));
  if (rc != 0) return *why = "cell-interp refused " + p.file + ": " + Slurp(err), std::nullopt;
  std::string perr;
  auto moves = ParseCellInterp(Slurp(out), mod->Capabilities(0).lathe, &perr, true);
  if (!perr.empty()) return *why = perr, std::nullopt;
  Contour c = FinishedContour(moves, p, 1e-4);
  if (c.elements.empty()) return *why = p.file + ": no feed move on its finish lines", std::nullopt;
  return c;
}

std::string Element(const Contour& c, std::size_t i) {
  if (i >= c.elements.size()) return "(none)";
  const Vec3& s = c.starts[i];
  char from[96];
  std::snprintf(from, sizeof from, "from (%.4f, %.4f, %.4f) ", s[0], s[1], s[2]);
  return "line " + std::to_string(c.elements[i].line) + ": " + from + Describe(c.elements[i]);
}

void Show(const std::string& name, const Contour& c) {
  std::cout << "  " << name << ":\n";
  for (std::size_t i = 0; i < c.elements.size(); ++i)
    std::cout << "    " << i + 1 << " " << Element(c, i) << "\n";
}

void Report(const Part& part, const PartProgram& a, const PartProgram& b, const Contour& ca,
            const Contour& cb, const Disagreement& d) {
  std::cout << part.name << ": " << b.file << " differs from " << a.file << " at element " << d.index << ": "
            << d.field << (d.detail.empty() ? "" : " (" + d.detail + ")") << "\n";
  std::cout << "  " << a.dialect << ": " << Element(ca, d.index - 1) << "\n  " << b.dialect << ": "
            << Element(cb, d.index - 1) << "\n";
}

// Every program of one part against its first; false on a refusal or a difference.
bool CheckPart(const PartOptions& o, const fs::path& dir, const fs::path& tmp) {
  Part part;
  std::string why;
  if (!ReadPart(dir.string(), &part, &why)) return std::cout << why << "\n", false;
  std::vector<Contour> contours;
  for (const PartProgram& p : part.programs) {
    auto c = RunProgram(o, dir, p, tmp, &why);
    if (!c) return std::cout << part.name << ": " << why << "\n", false;
    contours.push_back(*c);
    if (o.verbose) Show(p.file, *c);
  }
  if (o.plant) contours[1].elements[0].end[0] += 0.01;  // shows the comparer fails on a wrong value
  bool all = true;
  for (std::size_t i = 1; i < contours.size(); ++i) {
    if (auto d = CompareContours(contours[0], contours[i], 1e-3)) {
      Report(part, part.programs[0], part.programs[i], contours[0], contours[i], *d);
      all = false;
    } else {
      std::cout << part.name << ": " << part.programs[i].file << " and " << part.programs[0].file
                << " agree (" << contours[0].elements.size() << " elements)\n";
    }
  }
  return all;
}

}  // namespace

int Parts(int argc, char** argv) {
  PartOptions o;
  if (!ParsePartArgs(argc, argv, o)) {
    std::cerr << "usage: cell-oracle-gen parts [--dir DIR] [--part NAME] [--interp PATH] [--verbose] "
                 "[--plant]\n";
    return 2;
  }
  std::vector<fs::path> dirs;
  for (const auto& e : fs::directory_iterator(o.dir))
    if (e.is_directory() && (o.only.empty() || e.path().filename() == o.only)) dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  if (dirs.empty()) return std::cout << "oracle: no part in " << o.dir << "\n", 1;
  char tmpl[] = "/tmp/cell-oracle-parts.XXXXXX";
  if (!mkdtemp(tmpl)) return 2;
  bool all = true;
  for (const fs::path& d : dirs) all = CheckPart(o, d, tmpl) && all;
  fs::remove_all(tmpl);
  return all ? 0 : 1;
}

}  // namespace cell::oracle

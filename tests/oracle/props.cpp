// `cell-oracle-gen prop`: properties every program keeps (issue 33 item 2, docs/testing.md "Properties").
// Each property rewrites a generated block list into variants that state one motion in different words
// (absolute and incremental; inch and mm; a dialect's unit forms); cell-interp runs every variant and the
// moves must agree with the first variant's within the tolerance. No rs274 is needed.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>

#include "cell/oracle/oracle.h"
#include "run.h"

namespace fs = std::filesystem;

namespace cell::oracle {
namespace {

struct Variant {
  std::string name;
  std::vector<Block> blocks;
  std::string form;  // Module::WriteForm's form ("" the seed's)
  // Blocks [sub_first, sub_last) moved into the dialect's subprogram, called where they were (none: equal).
  std::size_t sub_first = 0, sub_last = 0;
  std::string prelude{};  // a transform's block, written after the program's header
  // The first variant's moves as this variant must make them (none: the same moves).
  std::function<void(std::vector<Move>&)> expect{};
};

struct Case {
  Caps caps;
  std::vector<Variant> variants;
  double tol = 1e-3;
};

// Absolute = incremental: the generated mix, every block absolute, every block incremental it can be.
Case AbsInc(const Module& mod, std::uint64_t seed, int count) {
  Case c{mod.Capabilities(seed), {}, 1e-3};
  auto blocks = Generate(c.caps, seed, count);
  c.variants = {{"absolute", Absolute(blocks), ""},
                {"generated", blocks, ""},
                {"incremental", Incremental(blocks, c.caps), ""}};
  for (const Block& b : blocks)
    if (b.m.inch) c.tol = 2e-3;  // rs274-free, but a program mixing units states positions on two grids
  return c;
}

// The unit forms of a dialect: which forms state an inch block list and which its mm conversion; `switching`:
// the unit may change mid-program (G70/G71 every 16 blocks); `mm_only`: forms compared on a mm grid of
// `mm_decimals` with no conversion (Okuma's 10 um system and its two exact mm twins).
struct UnitPlan {
  bool switching = false;
  std::vector<std::string> inch_forms{""}, mm_forms{""};
  std::vector<std::string> mm_only;
  int mm_decimals = 2;
};

UnitPlan PlanOf(const Module& mod) {
  if (mod.Name() == "emco") return {false, {"um", "decimal"}, {"um", "decimal"}, {}, 2};
  if (mod.Name() == "okuma")
    return {false, {"INCH", "0.0001INCH"}, {"1MM", "1UM"}, {"10UM", "1MM", "1UM"}, 2};
  return {true, {""}, {""}, {}, 2};
}

bool Every(std::size_t) {
  return true;
}
bool Alternate(std::size_t i) {
  return (i / 16) % 2 == 1;
}

// Units: an inch program and the same in mm. Inch positions on a 0.01 in grid (0.254 mm) and feeds on
// ConvertibleFeeds' step state the same numbers exactly in mm, so nothing rounds and 1e-3 mm holds (a 1e-4 in
// grid rounds by 5e-4 mm, and an interpreter mends an arc whose radii then differ by moving its centre).
// Odd seeds of a dialect with mm-only forms compare those.
Case Units(const Module& mod, std::uint64_t seed, int count) {
  UnitPlan plan = PlanOf(mod);
  Case c{mod.Capabilities(seed), {}, 1e-3};
  c.caps.unit_switch = false;
  if (!plan.mm_only.empty() && seed % 2 == 1) {
    c.caps.inch = false, c.caps.inch_only = false, c.caps.mm_decimals = plan.mm_decimals;
    auto blocks = Generate(c.caps, seed, count);
    for (const auto& f : plan.mm_only) c.variants.push_back({f, blocks, f});
    return c;
  }
  c.caps.inch = true, c.caps.inch_only = true, c.caps.inch_decimals = 2, c.caps.mm_decimals = 3;
  // A peck cycle whose back-off or clearance is another length in inch (EMCO's S02 counts the unit: 0.5 mm,
  // 0.05 in) makes other moves in the other unit: not drawn here.
  for (const Caps::Peck& p : c.caps.pecks) {
    auto other = [](double mm, double in) { return in > 0 && std::fabs(in * 25.4 - mm) > 1e-9; };
    if (!other(p.backoff, p.backoff_in) && !other(p.clearance, p.clearance_in)) continue;
    for (auto* codes : {&c.caps.cycles, &c.caps.cycles_per_rev})
      codes->erase(std::remove(codes->begin(), codes->end(), p.code), codes->end());
  }
  auto inch = ExactArcs(ConvertibleFeeds(Generate(c.caps, seed, count), c.caps), 2);
  auto mm = InchToMm(inch, c.caps, Every);
  for (const auto& f : plan.inch_forms) c.variants.push_back({"inch " + f, inch, f});
  for (const auto& f : plan.mm_forms) c.variants.push_back({"mm " + f, mm, f});
  if (plan.switching) c.variants.push_back({"switching", InchToMm(inch, c.caps, Alternate), ""});
  return c;
}

// Subprogram = inline: the blocks of a stretch moved into the dialect's subprogram and called once (the
// modes they set carry on after the call, as they would inline). Dialects without one: no variants.
Case Subprogram(const Module& mod, std::uint64_t seed, int count) {
  Case c{mod.Capabilities(seed), {}, 1e-3};
  auto blocks = Generate(c.caps, seed, count);
  for (const Block& b : blocks)
    if (b.m.inch) c.tol = 2e-3;
  std::size_t n = blocks.size();
  if (!mod.Subprogram() || n < 8) return c;
  c.variants = {{"inline", blocks, ""},
                {"early stretch called", blocks, "", n / 4, n / 2},
                {"late stretch called", blocks, "", n / 2, n - 2}};  // not the last block (EMCO ALARM 340)
  return c;
}

// Transforms give the transformed motion of the untransformed program: Balt-System MIR (ln 5665-5697,
// judgement call 13), URT (ln 5699-5728: the plane turned about the origin, counterclockwise positive) and
// SCF (ln 5730-5765), KT-APL MIR (ln 3615-3648: X1 inverts X about the current zero). No offsets, position
// sets or rotary axes (the transforms act about the current origin and on the configured axes), XY only (URT
// turns the interpolation plane: which one in G18/G19 the manual does not say).
Case Transforms(const Module& mod, std::uint64_t seed, int count) {
  Case c{mod.Capabilities(seed), {}, 1e-3};
  if (mod.Name() != "balt" && mod.Name() != "ktapl") return c;
  c.caps.offsets = false, c.caps.rotary = false, c.caps.rotary_linear = false, c.caps.position_set.clear();
  c.caps.planes = {17}, c.caps.swapped_planes = false;
  auto blocks = Generate(c.caps, seed, count);
  for (const Block& b : blocks)
    if (b.m.inch) c.tol = 2e-3;
  auto mirror = [](unsigned axes) { return [axes](std::vector<Move>& m) { MirrorMoves(m, axes); }; };
  c.variants = {{"plain", blocks, ""}};
  auto add = [&](const std::string& prelude, std::function<void(std::vector<Move>&)> expect) {
    c.variants.push_back({prelude, blocks, "", 0, 0, prelude, std::move(expect)});
  };
  if (mod.Name() == "ktapl") {
    add("(MIR,X1Y0)", mirror(1));
    add("(MIR,X0Y1)", mirror(2));
    add("(MIR,X1Y1)", mirror(3));
    return c;
  }
  add("(MIR,X)", mirror(1));
  add("(MIR,X,Y)", mirror(3));
  add("(URT,90)", [](std::vector<Move>& m) { RotateMoves(m, 90); });
  add("(URT,-30)", [](std::vector<Move>& m) { RotateMoves(m, -30); });
  add("(URT,30)\n(MIR,X)", [](std::vector<Move>& m) {  // URT first, MIR second (ln 5696)
    RotateMoves(m, 30);
    MirrorMoves(m, 1);
  });
  add("(SCF,2)", [](std::vector<Move>& m) { ScaleMoves(m, 2); });
  return c;
}

// The program text with blocks [first, last) in the dialect's subprogram, from the text Write gave: its
// header, its blocks (each with the mode words it needs) and its end.
struct Parts {
  std::string header, end;
};
Parts Split(const Program& p) {
  const auto& b = p.blocks_dialect;
  std::size_t blocks_len = 0;
  for (const auto& t : b) blocks_len += t.size() + 1;
  std::size_t after = p.dialect_text.rfind(b.back() + "\n") + b.back().size() + 1;
  std::string end = p.dialect_text.substr(after);
  return {p.dialect_text.substr(0, p.dialect_text.size() - end.size() - blocks_len), end};
}

std::string WithSubprogram(const Program& p, const SubprogramForm& f, std::size_t first, std::size_t last) {
  const auto& b = p.blocks_dialect;
  auto [out, end] = Split(p);
  std::string body;
  for (std::size_t i = first; i < last; ++i) body += b[i] + "\n";
  std::string definition = f.head + body + f.tail;
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (i == first) out += (f.in_place ? definition : "") + f.call + "\n";
    if (i < first || i >= last) out += b[i] + "\n";
  }
  return out + end + (f.in_place ? "" : definition);
}

std::string VariantText(const Module& mod, std::uint64_t seed, const Variant& v) {
  Program p = mod.WriteForm(v.blocks, seed, v.form);
  if (!v.prelude.empty()) {
    p.dialect_text.insert(Split(p).header.size(), v.prelude + "\n");
  }
  if (v.sub_last <= v.sub_first) return p.dialect_text;
  return WithSubprogram(p, *mod.Subprogram(), v.sub_first, v.sub_last);
}

using Property = Case (*)(const Module&, std::uint64_t, int);
const std::map<std::string, Property>& PropertyTable() {
  static const std::map<std::string, Property> table{
      {"absinc", AbsInc}, {"units", Units}, {"subprogram", Subprogram}, {"transforms", Transforms}};
  return table;
}

struct Options {
  std::string property = "all", dialect = "all", interp = "cell-interp", keep;
  std::uint64_t seed = 1;
  int blocks = 1000, chunk = 250;
  bool plant = false;  // move one end point of each later variant by 0.01 mm: the check must fail
};

bool ParseArgs(int argc, char** argv, Options& o) {
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    std::string v = i + 1 < argc ? argv[++i] : "";
    if (a == "--plant") {
      o.plant = true;
      --i;
    } else if (a == "--property")
      o.property = v;
    else if (a == "--dialect")
      o.dialect = v;
    else if (a == "--seed")
      o.seed = std::strtoull(v.c_str(), nullptr, 10);
    else if (a == "--blocks")
      o.blocks = std::atoi(v.c_str());
    else if (a == "--chunk")
      o.chunk = std::atoi(v.c_str());
    else if (a == "--interp")
      o.interp = v;
    else if (a == "--keep")
      o.keep = v;
    else
      return false;
  }
  return o.blocks > 0 && o.chunk > 0 &&
         (o.property == "all" || o.property == "nogouge" || o.property == "corners" ||
          o.property == "rapids" || PropertyTable().count(o.property));
}

// One variant through cell-interp: its moves, or the refusal in `error`.
std::vector<Move> Run(const Options& o, const Module& mod, const Program& p, const fs::path& dir,
                      const std::string& stem, std::string* error) {
  fs::path prog = dir / (stem + "." + mod.Extension()), params = dir / (stem + ".params");
  Spit(prog, p.dialect_text);
  Spit(params, p.params);
  fs::path out = dir / (stem + ".out"), err = dir / (stem + ".err");
  int rc = Shell(Quote(o.interp) + " --dialect " + mod.Name() +
                 (p.params.empty() ? "" : " --params " + Quote(params)) + " " + Quote(prog) + " >" +
                 Quote(out) + " 2>" + Quote(err));
  auto moves = ParseCellInterp(Slurp(out), mod.Capabilities(0).lathe, error);
  if (rc != 0 && error->empty()) *error = "cell-interp refused: " + Slurp(err);
  DropStill(moves);
  return moves;
}

// Every variant against the first; prints the first disagreement of each and keeps the programs.
bool CheckCase(const Options& o, const Module& mod, const std::string& prop, std::uint64_t seed,
               const Case& c, const fs::path& dir) {
  std::vector<Move> first;
  bool ok = true;
  for (std::size_t v = 0; v < c.variants.size(); ++v) {
    const Variant& var = c.variants[v];
    Program p = mod.WriteForm(var.blocks, seed, var.form);
    p.dialect_text = VariantText(mod, seed, var);
    std::string error;
    auto moves = Run(o, mod, p, dir, "v" + std::to_string(v), &error);
    std::optional<Disagreement> d;
    if (!error.empty()) d = Disagreement{moves.size(), "refusal", error};
    if (v == 0) first = moves;
    if (o.plant && v > 0 && moves.size() > 5) moves[5].end[0] += 0.01;
    std::vector<Move> expected = first;
    if (var.expect) var.expect(expected);
    if (!d && v > 0) d = Compare(expected, moves, c.tol);
    if (!d) continue;
    if (d->index <
        std::min(first.size(), moves.size()))  // the comparer names its sides cell-interp and rs274
      d->detail =
          "expected: " + Describe(expected[d->index]) + "\n  " + var.name + ": " + Describe(moves[d->index]);
    ok = false;
    std::cout << mod.Name() << " " << prop << ": program seed " << seed << ", variant '" << var.name
              << "' against '" << c.variants[0].name << "', move " << d->index + 1 << ": " << d->field
              << " differs\n  " << d->detail << "\n";
    if (!o.keep.empty()) {
      fs::create_directories(o.keep);
      for (std::size_t k : {std::size_t{0}, v})
        Spit(fs::path(o.keep) / (mod.Name() + "-" + prop + "-" + std::to_string(seed) + "-v" +
                                 std::to_string(k) + "." + mod.Extension()),
             VariantText(mod, seed, c.variants[k]));
    }
  }
  return ok;
}

}  // namespace

int Properties(int argc, char** argv) {
  Options o;
  if (!ParseArgs(argc, argv, o)) {
    std::cerr << "usage: cell-oracle-gen prop --property "
                 "absinc|units|subprogram|transforms|nogouge|corners|rapids|all --dialect "
                 "D|all --seed "
                 "S --blocks N "
                 "[--chunk M] [--interp PATH] [--keep DIR] [--plant]\n";
    return 2;
  }
  // `--dialect all`, one dialect, or a list (`emco,okuma`: ctest runs the lathes' nogouge beside the mills').
  std::vector<std::string> names;
  if (o.dialect == "all") names = ModuleNames();
  for (std::size_t at = 0; o.dialect != "all" && at <= o.dialect.size();) {
    std::size_t comma = std::min(o.dialect.find(',', at), o.dialect.size());
    names.push_back(o.dialect.substr(at, comma - at));
    at = comma + 1;
  }
  char tmpl[] = "/tmp/cell-oracle-prop.XXXXXX";
  if (!mkdtemp(tmpl)) return 2;
  bool all = true;
  for (const auto& [prop, fn] : PropertyTable()) {
    if (o.property != "all" && o.property != prop) continue;
    for (const std::string& name : names) {
      const Module* mod = FindModule(name);
      if (!mod) {
        std::cout << "oracle: no module for dialect " << name << "\n";
        return 2;
      }
      int programs = 0, failing = 0;
      bool applies = false;
      for (int done = 0, i = 0; done < o.blocks; done += o.chunk, ++i, ++programs) {
        std::uint64_t seed = ProgramSeed(o.seed, name + "/" + prop, i);
        Case c = fn(*mod, seed, std::min(o.chunk, o.blocks - done));
        applies = applies || !c.variants.empty();
        if (!CheckCase(o, *mod, prop, seed, c, tmpl)) ++failing;
      }
      if (applies)
        std::printf("%s %s: %d of %d programs keep the property\n", name.c_str(), prop.c_str(),
                    programs - failing, programs);
      else
        std::printf("%s %s: does not apply\n", name.c_str(), prop.c_str());
      all = all && failing == 0;
    }
  }
  PropRun run{o.interp, o.keep, o.seed, o.blocks, o.plant};
  if (o.property == "all" || o.property == "nogouge")
    for (const std::string& name : names) all = NoGouge(run, name, tmpl) == 0 && all;
  if (o.property == "all" || o.property == "corners")
    for (const std::string& name : names) all = Corners(run, name, tmpl) == 0 && all;
  if (o.property == "all" || o.property == "rapids")
    for (const std::string& name : names) all = Rapids(run, name, tmpl) == 0 && all;
  fs::remove_all(tmpl);
  return all ? 0 : 1;
}

}  // namespace cell::oracle

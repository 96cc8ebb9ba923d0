// cell-idlgen: reads the cell's IDL (the restricted subset DESIGN.md §3 allows) and
//  - rejects what breaks vendor neutrality: non-@final structs, unbounded strings or sequences,
//    keys that are not int32 or string, unions, optionals;
//  - writes meta.h: per struct its registered type name, keyed flag and a bounds check
//    (Fast CDR 1.0 never checks bounds, so the bus does it before writing);
//  - writes fill.h: a deterministic "every field non-default, strings and sequences at their
//    bound" filler that the interop tests use;
//  - writes cyclone_registry.c: type name -> idlc topic descriptor.
// Usage: cell-idlgen OUT_DIR file.idl...
#include <cctype>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Type {
  std::string kind;  // prim, string, seq, enum, struct
  std::string name;  // prim name / enum or struct name
  long bound = 0;    // string / seq bound
  std::string elem_kind, elem_name;
  long elem_bound = 0;
};

struct Member {
  Type type;
  std::string name;
  long array = 0;
  bool key = false;
};

struct Struct {
  std::string name;
  std::vector<Member> members;
  std::string file;
};

struct Enum {
  std::string name;
  std::vector<std::string> values;
};

std::string g_module;
std::vector<Struct> g_structs;
std::map<std::string, Enum> g_enums;
std::set<std::string> g_struct_names;

[[noreturn]] void Fail(const std::string& file, int line, const std::string& msg) {
  throw std::runtime_error(file + ":" + std::to_string(line) + ": error: " + msg);
}

struct Lexer {
  std::vector<std::pair<std::string, int>> toks;
  size_t i = 0;
  std::string file;
  Lexer(const std::string& text, std::string f) : file(std::move(f)) {
    int line = 1;
    for (size_t p = 0; p < text.size();) {
      char c = text[p];
      if (c == '\n') {
        ++line;
        ++p;
        continue;
      }
      if (std::isspace(static_cast<unsigned char>(c))) {
        ++p;
        continue;
      }
      if (c == '/' && p + 1 < text.size() && text[p + 1] == '/') {
        while (p < text.size() && text[p] != '\n') ++p;
        continue;
      }
      if (c == '#') {  // preprocessor lines (#include) are handled by the real generators
        while (p < text.size() && text[p] != '\n') ++p;
        continue;
      }
      if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '@') {
        size_t q = p + 1;
        while (q < text.size() && (std::isalnum(static_cast<unsigned char>(text[q])) || text[q] == '_')) ++q;
        toks.emplace_back(text.substr(p, q - p), line);
        p = q;
        continue;
      }
      if (c == ':' && p + 1 < text.size() && text[p + 1] == ':') {
        toks.emplace_back("::", line);
        p += 2;
        continue;
      }
      toks.emplace_back(std::string(1, c), line);
      ++p;
    }
  }
  bool done() const { return i >= toks.size(); }
  const std::string& peek() const {
    static const std::string eof = "<eof>";
    return done() ? eof : toks[i].first;
  }
  int line() const { return done() ? (toks.empty() ? 0 : toks.back().second) : toks[i].second; }
  std::string next() {
    if (done()) Fail(file, line(), "unexpected end of file");
    return toks[i++].first;
  }
  void expect(const std::string& s) {
    int l = line();
    std::string t = next();
    if (t != s) Fail(file, l, "expected '" + s + "', got '" + t + "'");
  }
  long number() {
    int l = line();
    std::string t = next();
    try {
      return std::stol(t);
    } catch (...) {
      Fail(file, l, "expected a number, got '" + t + "'");
    }
  }
};

const std::set<std::string> kPrims = {"boolean",
                                      "octet",
                                      "char",
                                      "short",
                                      "long",
                                      "float",
                                      "double",
                                      "unsigned short",
                                      "unsigned long",
                                      "long long",
                                      "unsigned long long"};

Type ParseType(Lexer& lx) {
  Type t;
  int l = lx.line();
  std::string w = lx.next();
  if (w == "unsigned") {
    std::string w2 = lx.next();
    if (w2 == "long" && lx.peek() == "long") {
      lx.next();
      w2 = "long long";
    }
    t.kind = "prim";
    t.name = "unsigned " + w2;
  } else if (w == "long" && lx.peek() == "long") {
    lx.next();
    t.kind = "prim";
    t.name = "long long";
  } else if (kPrims.count(w)) {
    t.kind = "prim";
    t.name = w;
  } else if (w == "string") {
    if (lx.peek() != "<") Fail(lx.file, l, "unbounded string: every string must be string<N>");
    lx.next();
    t.kind = "string";
    t.bound = lx.number();
    lx.expect(">");
  } else if (w == "sequence") {
    lx.expect("<");
    Type e = ParseType(lx);
    if (e.kind == "seq") Fail(lx.file, l, "nested sequences are not allowed");
    if (lx.peek() != ",") Fail(lx.file, l, "unbounded sequence: every sequence must be sequence<T, N>");
    lx.next();
    t.kind = "seq";
    t.bound = lx.number();
    lx.expect(">");
    t.elem_kind = e.kind;
    t.elem_name = e.name;
    t.elem_bound = e.bound;
  } else if (g_enums.count(w)) {
    t.kind = "enum";
    t.name = w;
  } else if (g_struct_names.count(w)) {
    t.kind = "struct";
    t.name = w;
  } else if (w == "wstring" || w == "any" || w == "union" || w == "map") {
    Fail(lx.file, l, "'" + w + "' is not allowed in cell IDL");
  } else {
    Fail(lx.file, l, "unknown type '" + w + "'");
  }
  return t;
}

void ParseFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  Lexer lx(ss.str(), path);
  int depth = 0;
  while (!lx.done()) {
    int l = lx.line();
    std::string w = lx.next();
    if (w == "module") {
      std::string m = lx.next();
      if (!g_module.empty() && g_module != m) Fail(path, l, "one module 'cell' only");
      g_module = m;
      lx.expect("{");
      ++depth;
    } else if (w == "}") {
      lx.expect(";");
      --depth;
    } else if (w == "enum") {
      Enum e;
      e.name = lx.next();
      lx.expect("{");
      while (true) {
        e.values.push_back(lx.next());
        std::string s = lx.next();
        if (s == "}") break;
        if (s != ",") Fail(path, lx.line(), "expected ',' or '}' in enum");
      }
      lx.expect(";");
      g_enums[e.name] = e;
    } else if (w == "@final" || w == "struct") {
      if (w == "@final")
        lx.expect("struct");
      else
        Fail(path, l, "struct without @final: every cell type must be @final (DESIGN.md §3)");
      Struct s;
      s.name = lx.next();
      s.file = path;
      lx.expect("{");
      while (lx.peek() != "}") {
        Member m;
        while (lx.peek().size() > 1 && lx.peek()[0] == '@') {
          int al = lx.line();
          std::string a = lx.next();
          if (a == "@key")
            m.key = true;
          else
            Fail(path, al, "annotation " + a + " is not allowed (only @key)");
        }
        int ml = lx.line();
        m.type = ParseType(lx);
        m.name = lx.next();
        if (lx.peek() == "[") {
          lx.next();
          m.array = lx.number();
          lx.expect("]");
        }
        lx.expect(";");
        if (m.key && !((m.type.kind == "prim" && m.type.name == "long") || m.type.kind == "string"))
          Fail(path, ml, "key '" + m.name + "' must be an int32 (long) or a bounded string");
        s.members.push_back(m);
      }
      lx.expect("}");
      lx.expect(";");
      g_struct_names.insert(s.name);
      g_structs.push_back(s);
    } else if (w == "@appendable" || w == "@mutable" || w == "@optional" || w == "union") {
      Fail(path, l, w + " is not allowed: types must be @final structs (DESIGN.md §3)");
    } else {
      Fail(path, l, "unexpected '" + w + "'");
    }
  }
  if (depth != 0) throw std::runtime_error(path + ": unbalanced braces");
}

std::string CxxPrim(const std::string& p) {
  static const std::map<std::string, std::string> m = {{"boolean", "bool"},
                                                       {"octet", "uint8_t"},
                                                       {"char", "char"},
                                                       {"short", "int16_t"},
                                                       {"long", "int32_t"},
                                                       {"float", "float"},
                                                       {"double", "double"},
                                                       {"unsigned short", "uint16_t"},
                                                       {"unsigned long", "uint32_t"},
                                                       {"long long", "int64_t"},
                                                       {"unsigned long long", "uint64_t"}};
  return m.at(p);
}

// Emits an expression that produces a non-default value of a scalar kind.
std::string FillScalar(const std::string& kind, const std::string& name, long bound,
                       const std::string& salt) {
  if (kind == "prim") {
    if (name == "boolean") return "true";
    if (name == "double" || name == "float")
      return "static_cast<" + CxxPrim(name) + ">(seed * 1000 + " + salt + " + 0.25)";
    if (name == "char") return "static_cast<char>('A' + (seed + " + salt + ") % 26)";
    return "static_cast<" + CxxPrim(name) + ">(1 + (seed * 7 + " + salt + ") % 100)";
  }
  if (kind == "enum") {
    size_t n = g_enums.at(name).values.size();
    std::string q = g_module + "::" + name;
    if (n < 2) return "static_cast<" + q + ">(0)";
    return "static_cast<" + q + ">(1 + (seed + " + salt + ") % " + std::to_string(n - 1) + ")";
  }
  if (kind == "string") return "FillString(" + std::to_string(bound) + ", seed + " + salt + ")";
  throw std::logic_error("FillScalar " + kind);
}

void Write(const std::string& path, const std::string& text) {
  std::ifstream old(path);
  std::stringstream ss;
  if (old) ss << old.rdbuf();
  if (old && ss.str() == text) return;  // keep mtime: no needless rebuilds
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error(path + ": cannot write");
}

std::string Basename(const std::string& p) {
  std::string b = p.substr(p.find_last_of('/') + 1);
  return b.substr(0, b.rfind('.'));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: cell-idlgen OUT_DIR file.idl...\n";
    return 2;
  }
  std::string out = argv[1];
  std::vector<std::string> files(argv + 2, argv + argc);
  try {
    for (auto& f : files) ParseFile(f);
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  const std::string& M = g_module;
  std::set<std::string> nested;
  for (auto& s : g_structs)
    for (auto& m : s.members) {
      if (m.type.kind == "struct") nested.insert(m.type.name);
      if (m.type.kind == "seq" && m.type.elem_kind == "struct") nested.insert(m.type.elem_name);
    }

  std::ostringstream meta;
  meta << "// Generated by cell-idlgen from idl/*.idl. Do not edit.\n#pragma once\n#include <cstdint>\n"
          "#include <string>\n";
  for (auto& f : files) meta << "#include \"" << Basename(f) << ".h\"\n";
  meta << "\nnamespace cell::idl {\n\ntemplate <class T> struct TypeMeta;\n\n";
  // Bounds checks, defined for every struct so nested ones can be called.
  for (auto& s : g_structs) {
    std::string q = M + "::" + s.name;
    meta << "inline bool CheckBounds(const " << q << "& v, std::string& why);\n";
  }
  for (auto& s : g_structs) {
    std::string q = M + "::" + s.name;
    meta << "inline bool CheckBounds(const " << q << "& v, std::string& why) {\n  (void)v; (void)why;\n";
    for (auto& m : s.members) {
      std::string acc = "v." + m.name + "()";
      if (m.type.kind == "seq") {
        meta << "  if (" << acc << ".size() > " << m.type.bound << ") { why = \"" << s.name << "." << m.name
             << ": \" + std::to_string(" << acc << ".size()) + \" elements, bound " << m.type.bound
             << "\"; return false; }\n";
        if (m.type.elem_kind == "struct")
          meta << "  for (const auto& e : " << acc << ") if (!CheckBounds(e, why)) return false;\n";
      } else if (m.type.kind == "struct") {
        if (m.array)
          meta << "  for (const auto& e : " << acc << ") if (!CheckBounds(e, why)) return false;\n";
        else
          meta << "  if (!CheckBounds(" << acc << ", why)) return false;\n";
      }
    }
    meta << "  return true;\n}\n";
  }
  for (auto& s : g_structs) {
    std::string q = M + "::" + s.name;
    bool keyed = false;
    for (auto& m : s.members) keyed = keyed || m.key;
    meta << "template <> struct TypeMeta<" << q << "> {\n  static constexpr const char* kName = \"" << M
         << "::" << s.name << "\";\n  static constexpr bool kKeyed = " << (keyed ? "true" : "false")
         << ";\n};\n";
  }
  meta << "\n}  // namespace cell::idl\n\n// Every struct that is not only a member of another: the topic "
          "types.\n"
          "#define CELL_IDL_FOR_EACH_TOPIC_TYPE(X) \\\n";
  for (auto& s : g_structs)
    if (!nested.count(s.name)) meta << "  X(" << M << "::" << s.name << ") \\\n";
  meta << "\n";

  std::ostringstream fill;
  fill << "// Generated by cell-idlgen. Test helper: every field non-default, strings and sequences at "
          "bound.\n"
          "#pragma once\n#include <string>\n#include \"meta.h\"\n\nnamespace cell::idl {\n\n"
          "inline std::string FillString(long bound, long seed) {\n  std::string s;\n"
          "  for (long i = 0; i < bound; ++i) s.push_back(static_cast<char>('a' + (seed + i) % 26));\n"
          "  return s;\n}\n\n";
  for (auto& s : g_structs) fill << "inline void Fill(" << M << "::" << s.name << "& v, long seed);\n";
  for (auto& s : g_structs) {
    fill << "inline void Fill(" << M << "::" << s.name << "& v, long seed) {\n";
    int salt = 0;
    for (auto& m : s.members) {
      ++salt;
      std::string acc = "v." + m.name + "()";
      std::string st = std::to_string(salt);
      if (m.type.kind == "seq") {
        fill << "  " << acc << ".resize(" << m.type.bound << ");\n  for (size_t i = 0; i < " << acc
             << ".size(); ++i) {\n";
        if (m.type.elem_kind == "struct")
          fill << "    Fill(" << acc << "[i], seed + " << st << " + static_cast<long>(i));\n";
        else
          fill << "    " << acc << "[i] = "
               << FillScalar(m.type.elem_kind, m.type.elem_name, m.type.elem_bound,
                             st + " + static_cast<long>(i)")
               << ";\n";
        fill << "  }\n";
      } else if (m.array) {
        fill << "  for (size_t i = 0; i < " << m.array << "; ++i) ";
        if (m.type.kind == "struct")
          fill << "Fill(" << acc << "[i], seed + " << st << " + static_cast<long>(i));\n";
        else
          fill << acc << "[i] = "
               << FillScalar(m.type.kind, m.type.name, m.type.bound, st + " + static_cast<long>(i)") << ";\n";
      } else if (m.type.kind == "struct") {
        fill << "  Fill(" << acc << ", seed + " << st << ");\n";
      } else {
        fill << "  " << acc << " = " << FillScalar(m.type.kind, m.type.name, m.type.bound, st) << ";\n";
      }
    }
    fill << "}\n";
  }
  fill << "\n}  // namespace cell::idl\n";

  std::ostringstream reg;
  reg << "/* Generated by cell-idlgen: type name -> idlc topic descriptor. */\n#include <string.h>\n";
  for (auto& f : files) reg << "#include \"" << Basename(f) << ".h\"\n";
  reg << "const dds_topic_descriptor_t* cell_cyclone_descriptor(const char* type_name) {\n";
  for (auto& s : g_structs)
    reg << "  if (strcmp(type_name, \"" << M << "::" << s.name << "\") == 0) return &" << M << "_" << s.name
        << "_desc;\n";
  reg << "  return NULL;\n}\n";

  try {
    Write(out + "/meta.h", meta.str());
    Write(out + "/fill.h", fill.str());
    Write(out + "/cyclone_registry.c", reg.str());
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}

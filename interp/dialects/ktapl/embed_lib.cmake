# Generates a C++ source holding the shipped KT-APL library (dialects/ktapl/lib/*.ktapl) as raw strings.
# Usage: cmake -DDIR=<lib dir> -DOUT=<file.cpp> -P embed_lib.cmake
file(GLOB files "${DIR}/*.ktapl")
list(SORT files)
set(body "")
foreach(f ${files})
  get_filename_component(name ${f} NAME_WE)
  file(READ ${f} text)
  string(APPEND body "    {\"${name}\", R\"KTAPLLIB(${text})KTAPLLIB\"},\n")
endforeach()
file(WRITE ${OUT}.tmp "// Generated from interp/dialects/ktapl/lib by embed_lib.cmake. Do not edit.
#include <map>
#include <optional>
#include <string>

#include \"cell/interp/ktapl.h\"

namespace cell::interp {

std::optional<std::string> KtaplStandardLibrary(const std::string& name) {
  static const std::map<std::string, std::string> kLib = {
${body}  };
  auto it = kLib.find(name);
  if (it == kLib.end()) return std::nullopt;
  return it->second;
}

}  // namespace cell::interp
")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)

# Generates a C++ source holding the page's own assets (www/index.html, style.css, app.js) as raw strings.
# Usage: cmake -DDIR=<www dir> -DOUT=<file.cpp> -P embed_www.cmake
file(READ ${DIR}/index.html html)
file(READ ${DIR}/style.css css)
file(READ ${DIR}/app.js js)
file(WRITE ${OUT}.tmp "// Generated from services/dashboard/www by embed_www.cmake. Do not edit.
namespace cell::dashboard {
extern const char* const kIndexHtml;
extern const char* const kStyleCss;
extern const char* const kAppJs;
const char* const kIndexHtml = R\"CELLWWW(${html})CELLWWW\";
const char* const kStyleCss = R\"CELLWWW(${css})CELLWWW\";
const char* const kAppJs = R\"CELLWWW(${js})CELLWWW\";
}  // namespace cell::dashboard
")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)

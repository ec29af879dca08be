# Writes a C++ source that holds the bytes of INPUT as `pintag::db::detail::<SYMBOL>` (a
# std::span<const unsigned char>). Run with `cmake -DINPUT=... -DOUTPUT=... -DSYMBOL=... -P`.
# Pure CMake, so the build needs no xxd or python.
file(READ "${INPUT}" hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
# 0xAB, per byte; then break the very long line every 32 bytes so compilers and editors cope.
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "((0x..,){32})" "\\1\n" bytes "${bytes}")
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${INPUT} by db/cmake/embed_file.cmake; do not edit.\n"
  "#include <cstddef>\n#include <span>\n\n"
  "namespace pintag::db::detail {\nnamespace {\n"
  "alignas(16) const unsigned char kBytes[${size}] = {\n${bytes}\n};\n}  // namespace\n"
  "extern const std::span<const unsigned char> ${SYMBOL}(kBytes, ${size});\n"
  "}  // namespace pintag::db::detail\n")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")

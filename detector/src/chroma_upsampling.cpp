#include "pintag/detector/chroma_upsampling.hpp"

namespace pintag {

std::string_view ToString(ChromaUpsampling upsampling) {
  switch (upsampling) {
    case ChromaUpsampling::kNone:
      return "none";
    case ChromaUpsampling::kBoth:
      return "4:2:0";
    case ChromaUpsampling::kAcross:
      return "4:2:2";
    case ChromaUpsampling::kDown:
      return "4:4:0";
  }
  return "none";
}

}  // namespace pintag

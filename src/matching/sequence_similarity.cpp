// Sequence matching: see sequence_similarity.hpp.
#include "toposlam/matching/sequence_similarity.hpp"

#include <stdexcept>
#include <string>

namespace toposlam {

std::vector<float> sequenceSimilarity(const std::vector<float>& similarity, const std::vector<std::uint8_t>& candidate,
                                      int queries, int references, int length) {
  if (queries < 0 || references < 0 || length < 1)
    throw std::invalid_argument("sequence similarity: needs queries, references >= 0 and a length >= 1 (got " +
                                std::to_string(length) + ")");
  const std::size_t cells = static_cast<std::size_t>(queries) * static_cast<std::size_t>(references);
  if (similarity.size() != cells || candidate.size() != cells)
    throw std::invalid_argument("sequence similarity: the matrices do not have queries x references cells");
  const auto cell = [references](int q, int r) {
    return static_cast<std::size_t>(q) * static_cast<std::size_t>(references) + static_cast<std::size_t>(r);
  };
  std::vector<float> out(cells, 0.f);
  for (int q = 0; q < queries; ++q) {
    for (int r = 0; r < references; ++r) {
      if (candidate[cell(q, r)] == 0) continue;
      double sum = 0.0;
      int used = 0;
      for (int k = 0; k < length && q - k >= 0 && r - k >= 0; ++k) {
        const std::size_t c = cell(q - k, r - k);
        if (candidate[c] == 0) continue;
        sum += similarity[c];
        ++used;
      }
      out[cell(q, r)] = static_cast<float>(sum / used);  // used >= 1: (q, r) itself is a candidate
    }
  }
  return out;
}

}  // namespace toposlam

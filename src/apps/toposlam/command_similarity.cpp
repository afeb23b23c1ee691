// `toposlam similarity A B`: the n-gram similarity of two images (thesis section 3.3.1), both ways and
// symmetric, with the unigram/bigram/trigram counts behind it for histograms and keypoints, as text or
// JSON. "A -> B" means A is the reference and B the query (NgramSimilarity::similarity(A, B)).
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "image_input.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/matching/similarity_preset.hpp"

namespace toposlam::cli {

namespace {

struct SimilarityOptions {
  std::string first;
  std::string second;
  std::string keypoints = "orb";
  bool json = false;
  std::string preset = "default";
};

// "2.450/5" style cell: effective count over the n-grams the reference could have had.
std::string countCell(double count, int possible) {
  std::ostringstream cell;
  cell << std::fixed << std::setprecision(3) << count << "/" << possible;
  return cell.str();
}

void printDirection(const std::string& name, const SimilarityBreakdown& b) {
  const NgramCounts& c = b.counts;
  std::cout << std::fixed << std::setprecision(4) << "similarity " << name << " = " << b.similarity
            << "  (histograms " << b.histogram_part << ", keypoints ";
  if (b.keypoint_part_available)
    std::cout << b.keypoint_part;
  else
    std::cout << "n/a";
  std::cout << ")\n";
  std::cout << "  " << std::left << std::setw(12) << "n-grams" << std::right << std::setw(14) << "unigrams"
            << std::setw(14) << "bigrams" << std::setw(14) << "trigrams" << "\n";
  std::cout << "  " << std::left << std::setw(12) << "histograms" << std::right;
  for (int n = 0; n < kMaxNgramOrder; ++n) std::cout << std::setw(14) << countCell(c.histogram[n], c.histogram_possible[n]);
  std::cout << "\n  " << std::left << std::setw(12) << "keypoints" << std::right;
  for (int n = 0; n < kMaxNgramOrder; ++n) std::cout << std::setw(14) << countCell(c.keypoint[n], c.keypoint_possible[n]);
  std::cout << "\n  matched keypoints " << c.matched_keypoints << " of " << c.query_keypoints << " (query)\n";
}

void writeCountArray(JsonWriter& json, std::string_view name, const std::array<double, kMaxNgramOrder>& v) {
  json.key(name).beginArray();
  for (double x : v) json.value(x);
  json.endArray();
}

void writeCountArray(JsonWriter& json, std::string_view name, const std::array<int, kMaxNgramOrder>& v) {
  json.key(name).beginArray();
  for (int x : v) json.value(x);
  json.endArray();
}

void writeDirection(JsonWriter& json, std::string_view name, const std::string& reference,
                    const std::string& query, const SimilarityBreakdown& b) {
  const NgramCounts& c = b.counts;
  json.key(name).beginObject().field("reference", reference).field("query", query);
  json.field("similarity", b.similarity).field("histogram_part", b.histogram_part);
  json.key("keypoint_part");
  if (b.keypoint_part_available)
    json.value(b.keypoint_part);
  else
    json.null();
  writeCountArray(json, "histogram_counts", c.histogram);
  writeCountArray(json, "histogram_matched", c.histogram_matched);
  writeCountArray(json, "histogram_possible", c.histogram_possible);
  writeCountArray(json, "keypoint_counts", c.keypoint);
  writeCountArray(json, "keypoint_matched", c.keypoint_matched);
  writeCountArray(json, "keypoint_possible", c.keypoint_possible);
  json.field("query_keypoints", c.query_keypoints).field("matched_keypoints", c.matched_keypoints);
  json.endObject();
}

void describe(const std::string& label, const std::string& path, const Fingerprint& f) {
  std::cout << label << ": " << path << " (" << f.image_width << "x" << f.image_height << ", "
            << f.subregions.size() << " subregions, " << f.keypointCount() << " " << toString(f.backend)
            << " keypoints)\n";
}

void runSimilarity(const SimilarityOptions& o) {
  const SimilarityPreset preset = similarityPreset(o.preset);
  VpackConfig config = preset.fingerprint;
  config.keypoints.backend = parseKeypointBackend(o.keypoints);
  const VpackExtractor extractor(config);
  const Fingerprint a = fingerprintImageFile(extractor, o.first);
  const Fingerprint b = fingerprintImageFile(extractor, o.second);
  const NgramSimilarity similarity(preset.similarity);
  const SimilarityBreakdown ab = similarity.explain(a, b);
  const SimilarityBreakdown ba = similarity.explain(b, a);
  const double symmetric = 0.5 * (ab.similarity + ba.similarity);
  if (o.json) {
    JsonWriter json(std::cout);
    json.beginObject().field("a", o.first).field("b", o.second).field("keypoint_backend", toString(a.backend));
    json.field("symmetric", symmetric);
    writeDirection(json, "a_to_b", o.first, o.second, ab);
    writeDirection(json, "b_to_a", o.second, o.first, ba);
    json.endObject();
    std::cout << "\n";
    return;
  }
  describe("A", o.first, a);
  describe("B", o.second, b);
  std::cout << std::fixed << std::setprecision(4) << "symmetric similarity = " << symmetric << "\n";
  printDirection("A -> B (reference A, query B)", ab);
  printDirection("B -> A (reference B, query A)", ba);
}

}  // namespace

void addSimilarityCommand(CLI::App& app) {
  auto options = std::make_shared<SimilarityOptions>();
  auto* cmd = app.add_subcommand("similarity",
                                 "n-gram similarity of two images, both ways and symmetric (thesis 3.3.1)");
  cmd->add_option("a", options->first, "First image")->required();
  cmd->add_option("b", options->second, "Second image")->required();
  addKeypointBackendOption(*cmd, options->keypoints);
  cmd->add_flag("--json", options->json, "Print JSON instead of text");
  cmd->add_option("--preset", options->preset, "Method preset: default (measured on real frames) or thesis")
      ->capture_default_str();
  cmd->callback([options] { runSimilarity(*options); });
}

}  // namespace toposlam::cli

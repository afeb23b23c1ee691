// `toposlam localize --places PLACES.csv --queries QUERIES.csv`: localises every query image among the
// labelled places (thesis section 3.3.2, PlaceLocalizer) and prints the thesis' Table 3.1 layout: for each
// probability threshold, how many queries reach it and the precision among them. Optionally writes one
// prediction per query (--out) and JSON (--json).
//
// Both CSV files hold `image,label` lines (paths relative to the CSV). Images sharing a label form one
// place with several reference fingerprints. Bad lines and unreadable images are reported on stderr as
// "file:line: problem" and skipped; the command fails only when no place or no query is usable. A path
// holding a comma is written in double quotes (RFC 4180), and --out quotes its fields the same way.
//
// --route: the queries are one traversal in file order and the places are in route order (the order of
// their labels' first appearance), so each query's place probabilities are filtered along the route
// (PlaceRouteFilter: stay or move on to the next place); the printed probability is the filtered one.
#include <algorithm>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include "commands.hpp"
#include "toposlam/platform/output_file.hpp"
#include "image_input.hpp"
#include "progress.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/labelled_image_list.hpp"
#include "toposlam/matching/place_localizer.hpp"
#include "toposlam/matching/place_route_filter.hpp"
#include "config_options.hpp"

namespace toposlam::cli {

namespace {

struct LocalizeOptions {
  std::string places;
  std::string queries;
  std::vector<double> thresholds = {0.5, 0.6, 0.7, 0.8, 0.9};
  std::string out;
  ConfigOptions config;  ///< -c, --set, --preset, --keypoints: the fingerprint and similarity sections
  bool normalise_counts = false;
  bool json = false;
  bool route = false;
  PlaceRouteFilterConfig route_filter;
};

struct Prediction {
  std::string image;
  std::string expected;   ///< the query's label from the CSV
  std::string predicted;  ///< label of the most probable place
  double probability = 0.0;
  bool correct = false;
  std::vector<double> probabilities;  ///< every place's (filtered along the route with --route), in place order
};

struct ThresholdRow {
  double threshold = 0.0;
  int reached = 0;  ///< queries whose best probability is >= threshold
  int correct = 0;  ///< among them, correctly labelled
  double precision() const { return reached > 0 ? static_cast<double>(correct) / reached : 0.0; }
};


/// Fingerprints one CSV entry; nullopt (and a "file:line: ..." message on stderr) when it is unusable.
std::optional<Fingerprint> fingerprintEntry(const VpackExtractor& extractor, const LabelledImage& entry,
                                            int& problems) {
  try {
    return fingerprintImageFile(extractor, entry.path);
  } catch (const std::exception& e) {
    // "PATH: no such file", "PATH: not a readable image ...", or "PATH: " + the extractor's complaint.
    std::cerr << entry.source << ": " << e.what() << "; skipped\n";
  }
  ++problems;
  return std::nullopt;
}

LabelledImageList readListReporting(const std::string& csv, int& problems) {
  LabelledImageList list = readLabelledImageList(csv);  // throws when the file cannot be opened
  for (const std::string& p : list.problems) std::cerr << p << "; skipped\n";
  problems += static_cast<int>(list.problems.size());
  return list;
}

void writePredictions(const std::string& path, const std::vector<Prediction>& predictions) {
  OutputFile out(path);  // temporary name, checked, renamed: a full disk is an error naming the file
  out << "image,expected,label,probability,correct\n";
  for (const Prediction& p : predictions)
    out << quoteCsvField(p.image) << "," << quoteCsvField(p.expected) << "," << quoteCsvField(p.predicted) << "," << std::fixed << std::setprecision(6)
        << p.probability << "," << (p.correct ? 1 : 0) << "\n";
  out.commit();
}

void runLocalize(const LocalizeOptions& o) {
  int problems = 0;
  const LabelledImageList place_list = readListReporting(o.places, problems);
  const LabelledImageList query_list = readListReporting(o.queries, problems);

  const DaemonConfig settings = commandConfig(o.config);  // toposlamd's fingerprint and similarity
  const VpackExtractor extractor(settings.fingerprint);

  // Places in order of their label's first appearance; several images with one label are its references.
  std::vector<LabelledPlace> places;
  std::map<std::string, std::size_t> place_index;
  Progress place_progress("localize", "place images", static_cast<std::int64_t>(place_list.images.size()));
  for (std::size_t i = 0; i < place_list.images.size(); ++i) {
    const LabelledImage& entry = place_list.images[i];
    if (std::optional<Fingerprint> f = fingerprintEntry(extractor, entry, problems)) {
      auto [it, inserted] = place_index.emplace(entry.label, places.size());
      if (inserted) places.push_back({entry.label, {}});
      places[it->second].references.push_back(std::move(*f));
    }
    place_progress.update(static_cast<std::int64_t>(i + 1));
  }
  place_progress.finish();
  if (places.empty())
    throw std::runtime_error(o.places + ": no usable place image (" + std::to_string(problems) +
                             " problems reported above)");

  PlaceLocalizerConfig config;
  config.similarity = settings.similarity;
  config.normalise_counts = o.normalise_counts;
  const PlaceLocalizer localizer(config, std::move(places));

  std::optional<PlaceRouteFilter> route;
  if (o.route) route.emplace(o.route_filter, localizer.placeCount());

  std::vector<Prediction> predictions;
  int unknown_labels = 0;
  Progress query_progress("localize", "queries", static_cast<std::int64_t>(query_list.images.size()));
  for (std::size_t i = 0; i < query_list.images.size(); ++i) {
    const LabelledImage& entry = query_list.images[i];
    if (std::optional<Fingerprint> f = fingerprintEntry(extractor, entry, problems)) {
      const Localization l = localizer.localize(*f);
      Prediction p;
      p.image = entry.path;
      p.expected = entry.label;
      p.probabilities = route ? route->update(l.probabilities) : l.probabilities;
      const auto best = std::max_element(p.probabilities.begin(), p.probabilities.end());
      p.predicted = localizer.place(static_cast<int>(best - p.probabilities.begin())).label;
      p.probability = *best;
      p.correct = p.predicted == p.expected;
      if (place_index.count(entry.label) == 0) ++unknown_labels;
      predictions.push_back(std::move(p));
    }
    query_progress.update(static_cast<std::int64_t>(i + 1));
  }
  query_progress.finish();
  if (predictions.empty())
    throw std::runtime_error(o.queries + ": no usable query image (" + std::to_string(problems) +
                             " problems reported above)");
  if (unknown_labels > 0)
    std::cerr << "toposlam localize: " << unknown_labels
              << " queries have a label that is no place's label (always counted as wrong)\n";

  std::vector<ThresholdRow> rows;
  for (double t : o.thresholds) {
    ThresholdRow row{t, 0, 0};
    for (const Prediction& p : predictions) {
      if (p.probability + 1e-12 < t) continue;
      ++row.reached;
      row.correct += p.correct ? 1 : 0;
    }
    rows.push_back(row);
  }
  const auto all_correct = std::count_if(predictions.begin(), predictions.end(), [](const Prediction& p) { return p.correct; });
  const double all_precision = static_cast<double>(all_correct) / static_cast<double>(predictions.size());
  const double chance = 1.0 / static_cast<double>(localizer.placeCount());

  if (!o.out.empty()) writePredictions(o.out, predictions);
  if (problems > 0) std::cerr << "toposlam localize: " << problems << " problems reported above; run continued\n";

  if (o.json) {
    JsonWriter json(std::cout);
    json.beginObject().field("places", localizer.placeCount()).field("place_images", static_cast<int>(place_list.images.size()));
    json.field("queries", static_cast<int>(predictions.size())).field("problems", problems);
    json.field("correct", static_cast<int>(all_correct)).field("precision", all_precision).field("chance", chance);
    json.field("route", route.has_value());
    json.key("thresholds").beginArray();
    for (const ThresholdRow& r : rows)
      json.beginObject().field("threshold", r.threshold).field("images", r.reached).field("correct", r.correct)
          .field("precision", r.precision()).endObject();
    json.endArray();
    json.key("predictions").beginArray();
    for (const Prediction& p : predictions) {
      json.beginObject().field("image", p.image).field("expected", p.expected).field("label", p.predicted)
          .field("probability", p.probability).field("correct", p.correct);
      json.key("probabilities").beginArray();
      for (double v : p.probabilities) json.value(v);
      json.endArray().endObject();
    }
    json.endArray().endObject();
    std::cout << "\n";
    return;
  }
  std::cout << localizer.placeCount() << " places, " << predictions.size() << " queries localised ("
            << problems << " problems)";
  if (route)
    std::cout << ", along the route (stay " << o.route_filter.stay_probability << ", jump "
              << o.route_filter.jump_weight << (o.route_filter.loop ? ", loop" : "") << ")";
  std::cout << "\n";
  std::cout << std::fixed << std::setprecision(2) << "all queries: " << all_correct << " correct, precision "
            << 100.0 * all_precision << "% (chance " << 100.0 * chance << "%)\n";
  std::cout << std::right << std::setw(10) << "Threshold" << std::setw(10) << "Images" << std::setw(12) << "Precision"
            << "\n";
  for (const ThresholdRow& r : rows) {
    std::cout << std::setw(10) << std::setprecision(2) << r.threshold << std::setw(10) << r.reached;
    if (r.reached > 0)
      std::cout << std::setw(11) << 100.0 * r.precision() << "%\n";
    else
      std::cout << std::setw(12) << "-" << "\n";
  }
}

}  // namespace

void addLocalizeCommand(CLI::App& app) {
  auto options = std::make_shared<LocalizeOptions>();
  auto* cmd = app.add_subcommand("localize", "Localise query images among labelled places (thesis 3.3.2, Table 3.1)");
  cmd->add_option("--places", options->places, "CSV of image,label: the places' reference images")
      ->required();
  cmd->add_option("--queries", options->queries, "CSV of image,label: query images with their true place")
      ->required();
  cmd->add_option("--thresholds", options->thresholds, "Probability thresholds of the table, comma-separated")
      ->delimiter(',')
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--out", options->out, "Write one prediction per query: image,expected,label,probability,correct");
  addConfigOptions(*cmd, options->config);
  addKeyAlias(*cmd, options->config, "--keypoints", "fingerprint.keypoints.backend");
  cmd->add_flag("--normalise-counts", options->normalise_counts,
                "Divide each place's n-gram counts by the n-grams its representative could have had");
  cmd->add_flag("--json", options->json, "Print JSON instead of the table");
  CLI::Option* route = cmd->add_flag("--route", options->route,
                "Queries are one traversal in file order through the places in route order (file order): "
                "filter each query's place probabilities along the route");
  cmd->add_option("--stay", options->route_filter.stay_probability,
                  "With --route: probability of staying in the place between two queries (the rest: the next place)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str()
      ->needs(route);
  cmd->add_option("--jump", options->route_filter.jump_weight,
                  "With --route: weight of moving to any place off the route (relocalisation)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str()
      ->needs(route);
  cmd->add_flag("!--no-loop", options->route_filter.loop,
                "With --route: the route is not a loop (the last place is not followed by the first)")
      ->needs(route);
  cmd->callback([options] { runLocalize(*options); });
}

}  // namespace toposlam::cli

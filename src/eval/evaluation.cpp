// Run folder + ground truth -> EvalResult, and its text / JSON / HTML forms (see evaluation.hpp).
#include "toposlam/core/markup_escape.hpp"
#include "toposlam/eval/evaluation.hpp"
#include "toposlam/eval/recognition.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "toposlam/core/json_writer.hpp"

namespace toposlam::eval {

namespace fs = std::filesystem;

std::vector<std::int64_t> splitTraversals(std::int64_t frame_count, int count) {
  std::vector<std::int64_t> starts;
  for (int t = 0; t < std::max(1, count); ++t) starts.push_back(frame_count * t / std::max(1, count));
  return starts;
}

namespace {
/// First frame of each traversal from the labels' traversal column; empty when the column is absent.
std::vector<std::int64_t> labelTraversalStarts(const std::vector<LabelRow>& labels) {
  if (labels.empty() || labels.front().traversal < 0) return {};
  std::vector<std::int64_t> starts{0};
  for (std::size_t f = 1; f < labels.size(); ++f) {
    if (labels[f].traversal != labels[f - 1].traversal) starts.push_back(static_cast<std::int64_t>(f));
  }
  return starts;
}
}  // namespace

Truth loadTruth(const std::string& path) {
  Truth truth;
  truth.path = path;
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".csv" || ext == ".CSV") {
    const CsvTable table = readCsv(path);
    const bool labels = std::find(table.header.begin(), table.header.end(), "room") != table.header.end();
    if (labels) {
      truth.kind = Truth::Kind::Labels;
      truth.labels = loadLabels(path);
      truth.traversal_starts = labelTraversalStarts(truth.labels);
    } else {
      truth.kind = Truth::Kind::Pairs;
      truth.pairs = loadLoopClosurePairs(path);
    }
  } else {
    truth.kind = Truth::Kind::Matrix;
    truth.matrix = loadLoopClosureImage(path);
  }
  return truth;
}

Truth loadTruth(const std::vector<std::string>& paths) {
  if (paths.empty())
    throw std::invalid_argument("--truth: give labels.csv, a loop-closure matrix image or a pairs CSV");
  Truth truth = loadTruth(paths.front());
  if (paths.size() > 1 && truth.traversal_starts.empty()) {
    truth.traversal_starts = {0};
    for (LabelRow& row : truth.labels) row.traversal = 0;
  }
  for (std::size_t k = 1; k < paths.size(); ++k) {
    const Truth more = loadTruth(paths[k]);
    if (truth.kind != Truth::Kind::Labels || more.kind != Truth::Kind::Labels) {
      throw std::invalid_argument("--truth: only labels.csv files can be combined (one per traversal); " +
                                  paths[k] + " or " + paths.front() +
                                  " is a loop-closure matrix or pairs file");
    }
    // Each file starts a traversal; a file with a traversal column may hold several.
    const auto offset = static_cast<std::int64_t>(truth.labels.size());
    const std::vector<std::int64_t> more_starts =
        more.traversal_starts.empty() ? std::vector<std::int64_t>{0} : more.traversal_starts;
    for (std::int64_t start : more_starts) truth.traversal_starts.push_back(offset + start);
    const int traversal_offset = truth.labels.empty() ? 0 : std::max(0, truth.labels.back().traversal) + 1;
    for (LabelRow row : more.labels) {
      row.frame += offset;
      row.traversal = traversal_offset + std::max(0, row.traversal);
      truth.labels.push_back(row);
    }
    truth.path += "+" + paths[k];
  }
  return truth;
}

std::vector<double> frameNodeProbabilities(const RunData& run) {
  std::map<int, double> of_place;
  if (run.topology) {
    for (const auto& step : run.topology->history) of_place[step.place] = step.probability;
  }
  std::vector<double> p(run.frames.size(), 1.0);
  for (std::size_t f = 0; f < run.frames.size(); ++f) {
    const auto it = of_place.find(run.frames[f].place);
    if (it != of_place.end()) p[f] = it->second;
  }
  return p;
}

std::vector<std::int64_t> predictedCuts(const RunData& run,
                                        const std::vector<std::int64_t>& traversal_starts) {
  const std::set<std::int64_t> starts(traversal_starts.begin(), traversal_starts.end());
  std::set<std::int64_t> cuts;
  for (const auto* list : {&run.places, &run.dropped_places}) {
    for (const auto& p : *list) {
      if (p.first > 0 && starts.count(p.first) == 0) cuts.insert(p.first);
    }
  }
  return {cuts.begin(), cuts.end()};
}

namespace {

std::string kindName(Truth::Kind k) {
  switch (k) {
    case Truth::Kind::Labels:
      return "labels";
    case Truth::Kind::Matrix:
      return "matrix";
    case Truth::Kind::Pairs:
      return "pairs";
  }
  return "?";
}

LoopClosureMatrix matrixFromPairs(const Truth& truth, const RunData& run) {
  std::map<std::string, int> frame_of_name;
  for (const auto& f : run.frames) {
    if (!f.name.empty()) frame_of_name.emplace(f.name, static_cast<int>(f.frame));
  }
  LoopClosureMatrix m;
  m.size = static_cast<int>(run.frames.size());
  m.same.assign(static_cast<std::size_t>(m.size) * static_cast<std::size_t>(m.size), 0);
  std::vector<std::string> names;
  for (const auto& f : run.frames) names.push_back(f.name);
  auto resolve = [&](const std::string& name, int line) {
    const auto it = frame_of_name.find(name);
    if (it != frame_of_name.end()) return it->second;
    // A name with or without a folder: "41.jpg" finds "samples/41.jpg", "ref/7.jpg" finds "ref/7.jpg".
    try {
      if (const int f = resolveFrameName(name, names); f >= 0) return f;
    } catch (const std::invalid_argument& e) {
      throw RunFileError(truth.path + ":" + std::to_string(line) + ": " + e.what());
    }
    throw RunFileError(truth.path + ":" + std::to_string(line) + ": frame '" + name + "' is not in " +
                       run.dir + "/frames.csv (column name)");
  };
  for (const auto& p : truth.pairs) {
    const int i = resolve(p.query, p.line), j = resolve(p.match, p.line);
    m.same[static_cast<std::size_t>(i * m.size + j)] = 1;
    m.same[static_cast<std::size_t>(j * m.size + i)] = 1;
  }
  return m;
}

}  // namespace

EvalResult evaluate(const RunData& run, const Truth& truth, const EvalOptions& options) {
  EvalResult result;
  result.run_dir = run.dir;
  result.truth_path = truth.path;
  result.truth_kind = kindName(truth.kind);
  result.frames = static_cast<int>(run.frames.size());
  result.places = static_cast<int>(run.places.size());
  result.dropped_places = static_cast<int>(run.dropped_places.size());
  const std::int64_t n = static_cast<std::int64_t>(run.frames.size());
  // loadRun checks this with file and line; a RunData built in memory gets the same refusal here.
  for (const auto* list : {&run.places, &run.dropped_places}) {
    for (const PlaceRecord& p : *list) {
      if (p.first < 0 || p.last >= n || p.representative < p.first || p.representative > p.last) {
        throw RunFileError(run.dir + ": place " + std::to_string(p.place) + " (frames " +
                           std::to_string(p.first) + ".." + std::to_string(p.last) + ", representative " +
                           std::to_string(p.representative) + ") does not lie inside the " +
                           std::to_string(n) + " frames of frames.csv");
      }
    }
  }
  // Traversals: the labels say (traversal column, one per labels file) > --traversals N (even split) >
  // one per source of `map`.
  const std::vector<std::int64_t> starts = !truth.traversal_starts.empty() ? truth.traversal_starts
                                           : options.traversals > 0 ? splitTraversals(n, options.traversals)
                                                                    : run.traversal_starts;
  if (!truth.traversal_starts.empty() && options.traversals > 0 &&
      static_cast<int>(truth.traversal_starts.size()) != options.traversals) {
    result.notes.push_back("--traversals " + std::to_string(options.traversals) +
                           " ignored: the ground truth has " + std::to_string(truth.traversal_starts.size()) +
                           " traversals (labels.csv column traversal, or one per labels file)");
  }
  result.traversals = static_cast<int>(starts.size());
  result.traversal_starts = starts;
  result.min_gap = options.min_gap >= 0 ? options.min_gap : (truth.kind == Truth::Kind::Labels ? 0 : 25);

  const bool has_nodes =
      std::any_of(run.frames.begin(), run.frames.end(), [](const FrameRecord& f) { return f.node >= 0; });
  std::vector<int> node_of_frame;
  for (const auto& f : run.frames) node_of_frame.push_back(f.node);
  const std::vector<double> probability = frameNodeProbabilities(run);

  std::vector<int> rooms;
  if (truth.kind == Truth::Kind::Labels) {
    if (static_cast<std::int64_t>(truth.labels.size()) != n) {
      throw RunFileError(truth.path + ": has " + std::to_string(truth.labels.size()) + " frames but " +
                         run.dir + "/frames.csv has " + std::to_string(n) +
                         " (give the labels of every traversal, in order)");
    }
    for (const auto& l : truth.labels) rooms.push_back(l.room);
  }

  // Loop closure.
  if (has_nodes) {
    LoopClosureTruth lct;
    if (truth.kind == Truth::Kind::Labels) {
      lct = truthFromRooms(rooms, result.min_gap);
      // By room labels (judged by pose instead below when the labels carry poses).
      std::vector<PlaceSpan> spans;
      for (const auto& p : run.places) spans.push_back(PlaceSpan{p.first, p.last, static_cast<int>(p.node)});
      result.place_revisits = scorePlaceRevisits(spans, rooms);
    } else {
      const LoopClosureMatrix m =
          truth.kind == Truth::Kind::Matrix ? truth.matrix : matrixFromPairs(truth, run);
      if (m.size != n) {
        throw RunFileError(truth.path + ": loop-closure matrix is " + std::to_string(m.size) + "x" +
                           std::to_string(m.size) + " but " + run.dir + "/frames.csv has " +
                           std::to_string(n) + " frames");
      }
      lct = truthFromMatrix(m, result.min_gap);
      std::vector<PlaceSpan> spans;
      for (const auto& p : run.places) spans.push_back(PlaceSpan{p.first, p.last, static_cast<int>(p.node)});
      result.place_revisits = scorePlaceRevisits(spans, m);
    }
    result.loop_closure = precisionRecall(lct, pairsFromAssignments(node_of_frame, probability));
    // Frame level (the literature's scoring), when frames.csv carries the detections of `map`.
    if (run.has_frame_matches) {
      std::vector<std::int64_t> match;
      std::vector<double> score;
      for (const auto& f : run.frames) {
        match.push_back(f.match);
        score.push_back(f.match_score);
      }
      const int gap = std::max(1, result.min_gap);
      RecognitionTruth rt;
      if (truth.kind == Truth::Kind::Labels) {
        rt = sequenceTruthFromRooms(rooms, gap);
      } else {
        rt = sequenceTruthFromMatrix(truth.kind == Truth::Kind::Matrix ? truth.matrix : matrixFromPairs(truth, run), gap);
      }
      result.frame_loop_closure = frameLoopClosures(match, score, rt);
    }
  } else {
    result.notes.push_back(
        "no topological nodes in frames.csv (a `segment` run?): no loop-closure or topology measures");
  }

  if (truth.kind != Truth::Kind::Labels) {
    result.notes.push_back("ground truth is a loop-closure " + result.truth_kind +
                           ": localisation, segmentation and room-level topology measures need labels.csv");
  } else {
    // Localisation: a node stands for the room most of its frames are in.
    if (has_nodes) {
      std::map<int, std::vector<int>> rooms_of_node;
      for (std::size_t f = 0; f < rooms.size(); ++f) {
        if (node_of_frame[f] >= 0) rooms_of_node[node_of_frame[f]].push_back(rooms[f]);
      }
      std::map<int, int> room_of_node;
      for (const auto& [node, rs] : rooms_of_node) room_of_node[node] = majority(rs);
      std::vector<LocalisationPrediction> predictions;
      for (std::size_t f = 0; f < rooms.size(); ++f) {
        if (node_of_frame[f] < 0 || rooms[f] < 0) continue;
        predictions.push_back(LocalisationPrediction{std::to_string(room_of_node[node_of_frame[f]]),
                                                     std::to_string(rooms[f]), probability[f]});
      }
      result.localisation = localisationTable(predictions, options.thresholds);
    }
    result.boundaries =
        scoreBoundaries(predictedCuts(run, starts), roomBoundaries(rooms, starts), options.tolerance);
    std::vector<std::int64_t> reps;
    for (const auto& p : run.places) reps.push_back(p.representative);
    result.places_per_traversal = placesPerTraversal(reps, rooms, starts);
    result.consistency = crossTraversalConsistency(reps, rooms, starts);
    if (has_nodes) {
      std::vector<int> place_node, place_room;
      for (const auto& p : run.places) {
        if (p.node < 0) continue;
        place_node.push_back(p.node);
        int r = rooms[static_cast<std::size_t>(p.representative)];
        if (r < 0) {
          std::vector<int> rs(rooms.begin() + p.first, rooms.begin() + p.last + 1);
          r = majority(rs);
        }
        place_room.push_back(r);
      }
      result.topology = scoreTopology(place_node, place_room);
      const bool has_pose = std::any_of(truth.labels.begin(), truth.labels.end(),
                                        [](const LabelRow& l) { return std::isfinite(l.x); });
      if (has_pose) {
        std::vector<GroundPose> poses;
        for (const LabelRow& l : truth.labels) poses.push_back(GroundPose{l.x, l.y, l.heading});
        std::vector<PlaceSpan> spans;
        for (const auto& p : run.places) spans.push_back(PlaceSpan{p.first, p.last, static_cast<int>(p.node)});
        result.place_revisits = scorePlaceRevisits(spans, poses);
        if (run.has_frame_matches) {
          std::vector<std::int64_t> match;
          for (const auto& f : run.frames) match.push_back(f.match);
          result.frame_matches_by_pose = scoreFrameMatchesByPose(match, poses);
        }
      }
    }
  }
  if (run.topology) {
    for (const auto& s : run.topology->history)
      result.best_topology_probability.push_back(s.best_topology_probability.value_or(0.0));
  }
  return result;
}

// ---------------------------------------------------------------- output

namespace {

// "curve": the precision-recall points of a loop-closure measure (place pairs or frame detections).
void writePrPoints(JsonWriter& json, const std::vector<PrPoint>& points) {
  json.key("curve").beginArray();
  for (const auto& p : points) {
    json.beginObject()
        .field("threshold", p.threshold)
        .field("true_positives", p.true_positives)
        .field("false_positives", p.false_positives)
        .field("precision", p.precision)
        .field("recall", p.recall)
        .endObject();
  }
  json.endArray();
}

}  // namespace

void writeEvalJson(std::ostream& out, const EvalResult& r) {
  JsonWriter json(out);
  json.beginObject();
  json.field("run", r.run_dir).field("truth", r.truth_path).field("truth_kind", r.truth_kind);
  json.field("frames", r.frames).field("places", r.places).field("dropped_places", r.dropped_places);
  json.field("traversals", r.traversals).field("min_gap", r.min_gap);
  if (r.localisation) {
    json.key("localisation").beginArray();
    for (const auto& row : *r.localisation) {
      json.beginObject()
          .field("threshold", row.threshold)
          .field("images", row.images)
          .field("correct", row.correct)
          .field("precision", row.precision)
          .endObject();
    }
    json.endArray();
  }
  if (r.loop_closure) {
    const PrCurve& c = *r.loop_closure;
    json.key("loop_closure").beginObject();
    json.field("positives", c.positives).field("predicted", c.predicted);
    json.field("recall_at_100_precision", c.recall_at_full_precision);
    json.field("threshold_at_100_precision", c.threshold_at_full_precision);
    json.field("average_precision", c.average_precision);
    writePrPoints(json, c.points);
    json.endObject();
  }
  if (r.frame_loop_closure) {
    const RecognitionScore& c = *r.frame_loop_closure;
    json.key("frame_loop_closure").beginObject();
    json.field("frames_with_match", c.queries_with_match).field("detections", c.detections);
    json.field("right_detections", c.top1_correct);
    json.field("recall_at_100_precision", c.recall_at_full_precision);
    json.field("threshold_at_100_precision", c.threshold_at_full_precision);
    json.field("average_precision", c.average_precision);
    writePrPoints(json, c.curve);
    json.endObject();
  }
  if (r.boundaries) {
    const BoundaryScore& b = *r.boundaries;
    json.key("segmentation").beginObject();
    json.field("tolerance", b.tolerance)
        .field("predicted_boundaries", b.predicted)
        .field("true_boundaries", b.truth)
        .field("matched", b.matched)
        .field("precision", b.precision)
        .field("recall", b.recall)
        .field("f1", b.f1)
        .field("mean_offset_frames", b.mean_offset);
    if (r.places_per_traversal) {
      json.key("places_per_traversal").beginArray();
      for (const auto& t : *r.places_per_traversal) {
        json.beginObject()
            .field("traversal", t.traversal)
            .field("places", t.places)
            .field("room_visits", t.room_visits)
            .endObject();
      }
      json.endArray();
    }
    if (r.consistency) {
      json.key("consistency").beginObject();
      json.field("eligible_rooms", r.consistency->eligible)
          .field("consistent_rooms", r.consistency->consistent)
          .field("rate", r.consistency->rate);
      json.key("rooms").beginArray();
      for (const auto& rc : r.consistency->rooms) {
        json.beginObject().field("room", rc.room);
        json.key("visits").beginArray();
        for (int v : rc.visits) json.value(v);
        json.endArray().key("places").beginArray();
        for (int v : rc.places) json.value(v);
        json.endArray().endObject();
      }
      json.endArray().endObject();
    }
    json.endObject();
  }
  if (r.topology) {
    const TopologyScore& t = *r.topology;
    json.key("topology").beginObject();
    json.field("nodes", t.nodes)
        .field("rooms", t.rooms)
        .field("one_to_one", t.one_to_one)
        .field("merged_nodes", t.merged_nodes)
        .field("split_rooms", t.split_rooms)
        .field("loop_closures", t.loop_closures)
        .field("wrong_loop_closures", t.wrong_loop_closures)
        .field("missed_loop_closures", t.missed_loop_closures);
    json.endObject();
  }
  if (r.place_revisits) {
    const PlaceRevisitScore& v = *r.place_revisits;
    json.key("place_revisits").beginObject();
    json.field("places", v.places)
        .field("revisits", v.revisits)
        .field("closed_right", v.closed_right)
        .field("missed", v.missed)
        .field("merged_with_previous", v.merged_with_previous)
        .field("wrong_closures", v.wrong_closures)
        .field("judged_by", v.by_pose ? "pose" : v.by_rooms ? "room labels" : "loop-closure truth");
    if (v.by_pose) json.field("radius_m", v.radius_m).field("max_heading_rad", v.max_heading_rad);
    json.field("min_overlap", v.min_overlap);
    json.endObject();
  }
  if (r.frame_matches_by_pose) {
    const FrameMatchPoseScore& v = *r.frame_matches_by_pose;
    json.key("frame_matches_by_pose").beginObject();
    json.field("matches", v.matches).field("right", v.right).field("wrong", v.wrong);
    json.field("radius_m", v.radius_m).field("max_heading_rad", v.max_heading_rad);
    json.endObject();
  }
  json.key("best_topology_probability").beginArray();
  for (double p : r.best_topology_probability) json.value(p);
  json.endArray();
  json.key("notes").beginArray();
  for (const auto& note : r.notes) json.value(note);
  json.endArray();
  json.endObject();
  out << "\n";
}

namespace {

std::string fmt(const char* format, double v) {
  if (!std::isfinite(v)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}
std::string percent(double v) { return fmt("%.2f%%", 100.0 * v); }

/// A table as header + rows of cells; rendered as aligned text or HTML.
struct Table {
  std::string title;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

std::vector<Table> tables(const EvalResult& r) {
  std::vector<Table> out;
  if (r.localisation) {
    Table t{
        "Localisation (thesis Table 3.1): frames whose node probability >= threshold, and how many of them "
        "are in the room their node stands for",
        {"threshold", "images", "correct", "precision"},
        {}};
    for (const auto& row : *r.localisation) {
      t.rows.push_back({fmt("%.1f", row.threshold), std::to_string(row.images), std::to_string(row.correct),
                        percent(row.precision)});
    }
    out.push_back(t);
  }
  if (r.loop_closure) {
    const PrCurve& c = *r.loop_closure;
    Table t{"Loop closure (frame pairs on one node in different visits; pairs within " +
                std::to_string(r.min_gap) + " frames not evaluated)",
            {"measure", "value"},
            {}};
    t.rows.push_back({"ground-truth pairs", std::to_string(c.positives)});
    t.rows.push_back({"predicted pairs", std::to_string(c.predicted)});
    t.rows.push_back({"recall at 100% precision", percent(c.recall_at_full_precision)});
    if (!c.points.empty()) {
      t.rows.push_back({"precision (all predictions)", percent(c.points.back().precision)});
      t.rows.push_back({"recall (all predictions)", percent(c.points.back().recall)});
    }
    t.rows.push_back({"average precision", fmt("%.3f", c.average_precision)});
    out.push_back(t);
  }
  if (r.frame_loop_closure) {
    const RecognitionScore& c = *r.frame_loop_closure;
    const std::int64_t right = c.top1_correct;
    Table t{"Frame-level loop closures (each frame's detected earlier frame, right when it is a true match at "
            "least " + std::to_string(std::max(1, r.min_gap)) + " frames back; score: frames.csv match_score)",
            {"measure", "value"},
            {}};
    t.rows.push_back({"frames with a true match", std::to_string(c.queries_with_match)});
    t.rows.push_back({"detections", std::to_string(c.detections)});
    t.rows.push_back({"right detections", std::to_string(right)});
    t.rows.push_back({"wrong detections", std::to_string(c.detections - right)});
    t.rows.push_back({"recall at 100% precision", percent(c.recall_at_full_precision)});
    if (!c.curve.empty()) {
      t.rows.push_back({"precision (all detections)", percent(c.curve.back().precision)});
      t.rows.push_back({"recall (all detections)", percent(c.curve.back().recall)});
    }
    out.push_back(t);
  }
  if (r.boundaries) {
    const BoundaryScore& b = *r.boundaries;
    Table t{"Segmentation: place cuts vs. room changes, tolerance " + std::to_string(b.tolerance) + " frames",
            {"cuts", "room changes", "matched", "precision", "recall", "F1", "mean offset (frames)"},
            {{std::to_string(b.predicted), std::to_string(b.truth), std::to_string(b.matched),
              percent(b.precision), percent(b.recall), fmt("%.3f", b.f1), fmt("%+.1f", b.mean_offset)}}};
    out.push_back(t);
  }
  if (r.places_per_traversal) {
    Table t{"Places per traversal", {"traversal", "places", "room visits"}, {}};
    for (const auto& row : *r.places_per_traversal) {
      t.rows.push_back(
          {std::to_string(row.traversal + 1), std::to_string(row.places), std::to_string(row.room_visits)});
    }
    out.push_back(t);
  }
  if (r.consistency && r.traversals > 1) {
    Table t{"Consistency across traversals: places per room in each traversal (rate " +
                percent(r.consistency->rate) + " = " + std::to_string(r.consistency->consistent) + " of " +
                std::to_string(r.consistency->eligible) + " rooms yield a place in every traversal)",
            {"room", "visits", "places"},
            {}};
    for (const auto& rc : r.consistency->rooms) {
      std::string visits, places;
      for (std::size_t k = 0; k < rc.visits.size(); ++k) {
        visits += (k ? " / " : "") + std::to_string(rc.visits[k]);
        places += (k ? " / " : "") + std::to_string(rc.places[k]);
      }
      t.rows.push_back({std::to_string(rc.room), visits, places});
    }
    out.push_back(t);
  }
  if (r.topology) {
    const TopologyScore& s = *r.topology;
    Table t{"Topology (most probable): nodes vs. rooms", {"measure", "value"}, {}};
    t.rows.push_back({"nodes", std::to_string(s.nodes)});
    t.rows.push_back({"rooms with a place", std::to_string(s.rooms)});
    t.rows.push_back({"nodes matching a room one-to-one", std::to_string(s.one_to_one)});
    t.rows.push_back({"merged nodes (span >= 2 rooms)", std::to_string(s.merged_nodes)});
    t.rows.push_back({"split rooms (on >= 2 nodes)", std::to_string(s.split_rooms)});
    t.rows.push_back({"loop closures", std::to_string(s.loop_closures)});
    t.rows.push_back({"wrong loop closures", std::to_string(s.wrong_loop_closures)});
    t.rows.push_back({"missed loop closures", std::to_string(s.missed_loop_closures)});
    out.push_back(t);
  }
  if (r.place_revisits) {
    const PlaceRevisitScore& v = *r.place_revisits;
    const std::string within =
        v.by_pose ? " of its frames from within " + fmt("%.1f m", v.radius_m) + " and " +
                        fmt("%.0f deg", v.max_heading_rad * 180.0 / 3.14159265358979323846) + ")"
                  : v.by_rooms ? " of its frames, by room labels: a frame shows its whole room)"
                               : " of its frames, by the loop-closure ground truth)";
    Table t{std::string(v.by_pose ? "Place revisits by pose" : "Place revisits") +
                " (a place revisits the earlier places that saw at least " + fmt("%.0f%%", 100.0 * v.min_overlap) +
                within,
            {"measure", "value"},
            {}};
    t.rows.push_back({"places", std::to_string(v.places)});
    t.rows.push_back({"revisits", std::to_string(v.revisits)});
    t.rows.push_back({"closed onto a node they revisit", std::to_string(v.closed_right) + " (" +
                                                             (v.revisits > 0 ? percent(static_cast<double>(v.closed_right) / v.revisits) : std::string("-")) + ")"});
    t.rows.push_back({"missed (a new node)", std::to_string(v.missed)});
    t.rows.push_back({"left on the previous place's node", std::to_string(v.merged_with_previous)});
    t.rows.push_back({"wrong closures", std::to_string(v.wrong_closures)});
    out.push_back(t);
  }
  if (r.frame_matches_by_pose) {
    const FrameMatchPoseScore& v = *r.frame_matches_by_pose;
    Table t{"Frame matches by pose (a published match is right when its frame was taken within " +
                fmt("%.1f m", v.radius_m) + " and " + fmt("%.0f deg", v.max_heading_rad * 180.0 / 3.14159265358979323846) +
                " of the frame's pose)",
            {"measure", "value"},
            {}};
    t.rows.push_back({"published matches", std::to_string(v.matches)});
    t.rows.push_back({"right", std::to_string(v.right)});
    t.rows.push_back({"wrong", std::to_string(v.wrong)});
    out.push_back(t);
  }
  if (!r.best_topology_probability.empty()) {
    const auto& p = r.best_topology_probability;
    double mean = 0;
    for (double v : p) mean += v;
    mean /= static_cast<double>(p.size());
    Table t{"Probability of the most probable topology", {"measure", "value"}, {}};
    t.rows.push_back({"after the last place", fmt("%.3f", p.back())});
    t.rows.push_back({"mean over places", fmt("%.3f", mean)});
    t.rows.push_back({"minimum", fmt("%.3f", *std::min_element(p.begin(), p.end()))});
    out.push_back(t);
  }
  return out;
}

}  // namespace

std::string formatEvalText(const EvalResult& r) {
  std::ostringstream out;
  out << "run " << r.run_dir << " vs. " << r.truth_kind << " " << r.truth_path << ": " << r.frames
      << " frames, " << r.places << " places (" << r.dropped_places << " dropped), " << r.traversals
      << " traversal(s)\n";
  for (const Table& t : tables(r)) {
    out << "\n" << t.title << "\n";
    std::vector<std::size_t> width(t.header.size(), 0);
    for (std::size_t c = 0; c < t.header.size(); ++c) {
      width[c] = t.header[c].size();
      for (const auto& row : t.rows) width[c] = std::max(width[c], row[c].size());
    }
    auto line = [&](const std::vector<std::string>& cells) {
      out << " ";
      for (std::size_t c = 0; c < cells.size(); ++c) {
        out << " " << std::string(width[c] - cells[c].size(), ' ') << cells[c];
      }
      out << "\n";
    };
    line(t.header);
    for (const auto& row : t.rows) line(row);
  }
  for (const auto& note : r.notes) out << "\nnote: " << note << "\n";
  return out.str();
}

std::string formatEvalHtml(const EvalResult& r) {
  std::ostringstream out;
  for (const Table& t : tables(r)) {
    out << "<h3 class=\"eval\">" << escapeMarkup(t.title) << "</h3>\n<table class=\"eval\">\n<tr>";
    for (const auto& h : t.header) out << "<th>" << escapeMarkup(h) << "</th>";
    out << "</tr>\n";
    for (const auto& row : t.rows) {
      out << "<tr>";
      for (const auto& cell : row) out << "<td>" << escapeMarkup(cell) << "</td>";
      out << "</tr>\n";
    }
    out << "</table>\n";
  }
  for (const auto& note : r.notes) out << "<p class=\"note\">" << escapeMarkup(note) << "</p>\n";
  return out.str();
}

}  // namespace toposlam::eval

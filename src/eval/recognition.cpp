// Place recognition measures: see recognition.hpp.
#include "toposlam/eval/recognition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace toposlam::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

RecognitionTruth emptyTruth(int queries, int references) {
  RecognitionTruth t;
  t.queries = queries;
  t.references = references;
  t.state.assign(static_cast<std::size_t>(queries) * static_cast<std::size_t>(references), std::int8_t{-1});
  return t;
}

bool endsWithPath(const std::string& path, const std::string& name) {
  if (path == name) return true;
  if (path.size() <= name.size()) return false;
  return path.compare(path.size() - name.size(), name.size(), name) == 0 &&
         path[path.size() - name.size() - 1] == '/';
}

}  // namespace

RecognitionTruth sequenceTruthFromMatrix(const LoopClosureMatrix& matrix, int min_gap) {
  if (min_gap < 1) throw std::invalid_argument("min_gap must be >= 1 (a frame is no candidate of itself)");
  RecognitionTruth t = emptyTruth(matrix.size, matrix.size);
  for (int i = 0; i < matrix.size; ++i) {
    for (int j = 0; j + min_gap <= i; ++j) {
      t.state[static_cast<std::size_t>(i) * static_cast<std::size_t>(matrix.size) + static_cast<std::size_t>(j)] =
          matrix.at(i, j) || matrix.at(j, i) ? 1 : 0;
    }
  }
  return t;
}

RecognitionTruth sequenceTruthFromRooms(const std::vector<int>& rooms, int min_gap) {
  if (min_gap < 1) throw std::invalid_argument("min_gap must be >= 1 (a frame is no candidate of itself)");
  const int n = static_cast<int>(rooms.size());
  const std::vector<int> visit = visitIds(rooms);
  RecognitionTruth t = emptyTruth(n, n);
  for (int i = 0; i < n; ++i) {
    if (rooms[i] < 0) continue;
    for (int j = 0; j + min_gap <= i; ++j) {
      if (rooms[j] < 0) continue;
      std::int8_t state = 0;
      if (rooms[i] == rooms[j]) state = visit[static_cast<std::size_t>(i)] != visit[static_cast<std::size_t>(j)] ? 1 : -1;
      t.state[static_cast<std::size_t>(i) * static_cast<std::size_t>(n) + static_cast<std::size_t>(j)] = state;
    }
  }
  return t;
}

RecognitionTruth crossTruth(int queries, int references, const std::vector<std::uint8_t>& same) {
  if (same.size() != static_cast<std::size_t>(queries) * static_cast<std::size_t>(references))
    throw std::invalid_argument("cross truth: the same-place table does not have queries x references cells");
  RecognitionTruth t = emptyTruth(queries, references);
  for (std::size_t k = 0; k < same.size(); ++k) t.state[k] = same[k] != 0 ? 1 : 0;
  return t;
}

int resolveFrameName(const std::string& name, const std::vector<std::string>& paths) {
  int found = -1;
  for (std::size_t k = 0; k < paths.size(); ++k) {
    if (!endsWithPath(paths[k], name)) continue;
    if (found >= 0)
      throw std::invalid_argument("frame name '" + name + "' matches both " + paths[static_cast<std::size_t>(found)] +
                                  " and " + paths[k]);
    found = static_cast<int>(k);
  }
  return found;
}

RecognitionScore scoreRecognition(const std::vector<float>& similarity, const RecognitionTruth& truth) {
  if (similarity.size() != truth.state.size())
    throw std::invalid_argument("recognition: the similarity matrix has " + std::to_string(similarity.size()) +
                                " cells, the ground truth " + std::to_string(truth.state.size()));
  RecognitionScore score;
  score.best_reference.assign(static_cast<std::size_t>(truth.queries), -1);
  std::vector<std::pair<float, bool>> pairs;  // every candidate pair: similarity, same place
  struct Detection {
    float similarity;
    bool correct;
  };
  std::vector<Detection> detections;
  for (int q = 0; q < truth.queries; ++q) {
    int best = -1;
    float best_similarity = -std::numeric_limits<float>::infinity();
    bool has_match = false;
    for (int r = 0; r < truth.references; ++r) {
      const std::int8_t s = truth.at(q, r);
      if (s < 0) continue;
      const float v = similarity[static_cast<std::size_t>(q) * static_cast<std::size_t>(truth.references) +
                                 static_cast<std::size_t>(r)];
      pairs.emplace_back(v, s == 1);
      has_match = has_match || s == 1;
      if (best < 0 || v > best_similarity) {
        best = r;
        best_similarity = v;
      }
    }
    if (best < 0) continue;
    ++score.queries;
    score.best_reference[static_cast<std::size_t>(q)] = best;
    const bool correct = truth.at(q, best) == 1;
    if (has_match) {
      ++score.queries_with_match;
      if (correct) ++score.top1_correct;
    }
    detections.push_back({best_similarity, correct});
  }

  // AUC by ranks (Mann-Whitney U), ties counted one half.
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  double positive_rank_sum = 0.0;
  for (std::size_t k = 0; k < pairs.size();) {
    std::size_t end = k;
    while (end < pairs.size() && pairs[end].first == pairs[k].first) ++end;
    const double mean_rank = 0.5 * static_cast<double>(k + 1 + end);  // ranks k+1 .. end
    for (std::size_t t = k; t < end; ++t) {
      if (pairs[t].second) {
        positive_rank_sum += mean_rank;
        ++score.positive_pairs;
      } else {
        ++score.negative_pairs;
      }
    }
    k = end;
  }
  if (score.positive_pairs > 0 && score.negative_pairs > 0) {
    const double p = static_cast<double>(score.positive_pairs);
    const double n = static_cast<double>(score.negative_pairs);
    score.auc = (positive_rank_sum - p * (p + 1.0) / 2.0) / (p * n);
  } else {
    score.auc = kNaN;
  }
  score.top1 = score.queries_with_match > 0
                   ? static_cast<double>(score.top1_correct) / static_cast<double>(score.queries_with_match)
                   : kNaN;

  std::vector<ScoredDetection> scored;
  for (const Detection& d : detections) scored.push_back({d.similarity, d.correct});
  detectionCurve(scored, score);
  return score;
}

void detectionCurve(std::vector<ScoredDetection> detections, RecognitionScore& score) {
  // Precision-recall of the detections, accepted from the highest score down.
  std::stable_sort(detections.begin(), detections.end(),
                   [](const ScoredDetection& a, const ScoredDetection& b) { return a.score > b.score; });
  std::int64_t tp = 0, fp = 0;
  double previous_recall = 0.0;
  for (std::size_t k = 0; k < detections.size(); ++k) {
    if (detections[k].correct)
      ++tp;
    else
      ++fp;
    if (k + 1 < detections.size() && detections[k + 1].score == detections[k].score) continue;
    PrPoint point;
    point.threshold = detections[k].score;
    point.true_positives = tp;
    point.false_positives = fp;
    point.precision = static_cast<double>(tp) / static_cast<double>(tp + fp);
    point.recall = score.queries_with_match > 0
                       ? static_cast<double>(tp) / static_cast<double>(score.queries_with_match)
                       : kNaN;
    if (score.queries_with_match > 0) {
      score.average_precision += (point.recall - previous_recall) * point.precision;
      previous_recall = point.recall;
      if (fp == 0 && point.recall > score.recall_at_full_precision) {
        score.recall_at_full_precision = point.recall;
        score.threshold_at_full_precision = point.threshold;
      }
    }
    score.curve.push_back(point);
  }
  if (score.queries_with_match == 0) score.average_precision = kNaN;
}

RecognitionScore frameLoopClosures(const std::vector<std::int64_t>& match, const std::vector<double>& score_of_frame,
                                   const RecognitionTruth& truth) {
  if (truth.queries != truth.references || match.size() != static_cast<std::size_t>(truth.queries) ||
      score_of_frame.size() != match.size())
    throw std::invalid_argument("frame loop closures: " + std::to_string(match.size()) + " frames, the ground truth has " +
                                std::to_string(truth.queries));
  RecognitionScore score;
  score.best_reference.assign(match.size(), -1);
  std::vector<ScoredDetection> detections;
  for (int q = 0; q < truth.queries; ++q) {
    bool has_candidate = false, has_match = false;
    for (int r = 0; r < truth.references; ++r) {
      const std::int8_t s = truth.at(q, r);
      has_candidate = has_candidate || s >= 0;
      has_match = has_match || s == 1;
      if (s == 1) ++score.positive_pairs;
      if (s == 0) ++score.negative_pairs;
    }
    if (!has_candidate) continue;
    ++score.queries;
    if (has_match) ++score.queries_with_match;
    const std::int64_t m = match[static_cast<std::size_t>(q)];
    if (m < 0 || m >= truth.references) continue;
    score.best_reference[static_cast<std::size_t>(q)] = static_cast<int>(m);
    // A detection of a frame that is no candidate (too close in time) is wrong: nothing was recognised.
    const bool correct = truth.at(q, static_cast<int>(m)) == 1;
    if (correct && has_match) ++score.top1_correct;
    detections.push_back({static_cast<float>(score_of_frame[static_cast<std::size_t>(q)]), correct});
  }
  score.auc = kNaN;
  score.top1 = score.queries_with_match > 0
                   ? static_cast<double>(score.top1_correct) / static_cast<double>(score.queries_with_match)
                   : kNaN;
  score.detections = static_cast<int>(detections.size());
  detectionCurve(detections, score);
  return score;
}

}  // namespace toposlam::eval

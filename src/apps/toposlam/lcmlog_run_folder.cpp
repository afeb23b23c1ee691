// Run folder from an LCM log; see the header.
#include "lcmlog_run_folder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "offline_run_io.hpp"
#include "toposlam/run_folder/run_folder.hpp"

namespace toposlam::cli {

namespace fs = std::filesystem;

namespace {

std::string frameName(std::int64_t frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%06lld.jpg", static_cast<long long>(frame));
  return name;
}

}  // namespace

void writeRunFolderFromLog(const LoggedRun& run, const std::string& log_path, const fs::path& dir) {
  if (run.frames.empty())
    throw std::runtime_error(log_path + ": no place estimates (TOPOSLAM_PLACE) in " + std::to_string(run.events) +
                             " events: not a log of toposlamd, or its channels are renamed (give the daemon's "
                             "config with -c)");
  std::int64_t count = 0;
  for (const LoggedFrame& f : run.frames) count = std::max(count, f.frame + 1);
  for (const LoggedPlace& p : run.places) count = std::max(count, p.last_frame + 1);
  const auto n = static_cast<std::size_t>(count);

  // Per frame: time (NaN until known), lambda2, place, node.
  std::vector<double> time(n, std::nan("")), lambda2(n, std::nan(""));
  std::vector<int> place(n, -1), node(n, -1);
  // The per-frame answer as published (place_t.match_*): frames.csv's loop-closure columns, so `eval`
  // scores exactly what a subscriber received.
  std::vector<std::int64_t> match(n, -1);
  std::vector<double> match_score(n, 0.0);
  bool any_match = false;
  for (const LoggedFrame& f : run.frames) {
    if (f.frame < 0) continue;
    time[static_cast<std::size_t>(f.frame)] = f.time_s;
    lambda2[static_cast<std::size_t>(f.frame)] = f.lambda2;
    if (f.match_frame >= 0 && f.match_frame < f.frame) {
      match[static_cast<std::size_t>(f.frame)] = f.match_frame;
      match_score[static_cast<std::size_t>(f.frame)] = f.match_score;
      any_match = true;
    }
  }
  // Missing times: interpolated between the known neighbours (held at the ends).
  std::size_t previous = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isnan(time[i])) continue;
    if (previous == n) {
      for (std::size_t j = 0; j < i; ++j) time[j] = time[i];
    } else {
      for (std::size_t j = previous + 1; j < i; ++j)
        time[j] = time[previous] + (time[i] - time[previous]) * static_cast<double>(j - previous) /
                                       static_cast<double>(i - previous);
    }
    previous = i;
  }
  for (std::size_t j = previous + 1; j < n && previous < n; ++j) time[j] = time[previous];

  // The node of each place: the last topology's (the most probable map at the end), else the place event's.
  std::map<int, int> node_of_place;
  for (const LoggedPlace& p : run.places) node_of_place[p.place] = p.node;
  if (run.topology)
    for (const TopologyNode& t : run.topology->nodes)
      for (int p : t.places) node_of_place[p] = t.id;
  for (const LoggedPlace& p : run.places)
    for (std::int64_t f = std::max<std::int64_t>(0, p.first_frame); f <= p.last_frame && f < count; ++f) {
      place[static_cast<std::size_t>(f)] = p.place;
      node[static_cast<std::size_t>(f)] = node_of_place[p.place];
    }

  createRunFolder(dir);
  std::vector<FrameRecord> frames(n);
  for (std::size_t i = 0; i < n; ++i) {
    frames[i].frame = static_cast<std::int64_t>(i);
    frames[i].time_s = time[i];
    frames[i].name = frameName(static_cast<std::int64_t>(i));
    frames[i].lambda2 = lambda2[i];
    frames[i].place = place[i];
    frames[i].node = node[i];
    frames[i].match = match[i];
    frames[i].match_score = match_score[i];
  }
  writeFrames(dir, frames, any_match ? FrameColumns::WithLoopClosures : FrameColumns::Segmentation);
  std::vector<PlaceRecord> places;
  for (const LoggedPlace& p : run.places)
    places.push_back(PlaceRecord{p.place, 0, p.first_frame, p.last_frame, p.representative_frame, p.keypoints,
                                 node_of_place[p.place], ""});
  writePlaces(dir, places);
  TopologyFile topology;
  if (run.topology) {
    topology.probability = run.topology->probability;
    topology.particles = run.topology->particles;
    for (const TopologyNode& t : run.topology->nodes)
      topology.nodes.push_back(TopologyFile::Node{t.id, t.places, t.representative_frames, {}});
    for (const TopologyEdge& e : run.topology->edges)
      topology.edges.push_back(TopologyFile::Edge{e.from, e.to, e.count});
  }
  for (const LoggedPlace& p : run.places) {
    TopologyFile::Step& step = topology.history.emplace_back();
    step.place = p.place;
    step.node = p.node;
    step.probability = p.probability;
    step.is_new = p.is_new;
  }
  writeTopology(dir, topology);
  // The representatives' thumbnails, named as frames.csv names their frames: the report shows them.
  fs::create_directories(dir / run_files::kFramesFolder);
  for (const LoggedPlace& p : run.places) {
    if (p.thumbnail_jpeg.empty()) continue;
    OutputFile out = openOutput(dir / run_files::kFramesFolder / frameName(p.representative_frame));
    out.write(reinterpret_cast<const char*>(p.thumbnail_jpeg.data()), static_cast<std::streamsize>(p.thumbnail_jpeg.size()));
    out.commit();
  }
  writeSettings(dir, {{"source", "lcmlog:" + fs::absolute(log_path).string()},
                      {"log events", std::to_string(run.events)},
                      {"place estimates", std::to_string(run.frames.size())},
                      {"place events", std::to_string(run.places.size())}});
}

}  // namespace toposlam::cli

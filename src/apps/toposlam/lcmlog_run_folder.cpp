// Run folder from an LCM log; see the header.
#include "lcmlog_run_folder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "offline_run_io.hpp"
#include "toposlam/core/json_writer.hpp"

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
  for (const LoggedFrame& f : run.frames) {
    if (f.frame < 0) continue;
    time[static_cast<std::size_t>(f.frame)] = f.time_s;
    lambda2[static_cast<std::size_t>(f.frame)] = f.lambda2;
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

  createRunFolder(dir.string());
  {
    OutputFile out = openOutput(dir / "frames.csv");
    out << "frame,time,name,lambda2,place,node\n";
    char line[160];
    for (std::size_t i = 0; i < n; ++i) {
      std::string l2;
      if (!std::isnan(lambda2[i])) {
        char text[32];
        std::snprintf(text, sizeof text, "%.6f", lambda2[i]);
        l2 = text;
      }
      std::snprintf(line, sizeof line, "%zu,%.6f,%s,%s,%d,%d\n", i, time[i], frameName(static_cast<std::int64_t>(i)).c_str(),
                    l2.c_str(), place[i], node[i]);
      out << line;
    }
    out.commit();
  }
  {
    OutputFile out = openOutput(dir / "places.csv");
    out << "place,first,last,representative,keypoints,node\n";
    for (const LoggedPlace& p : run.places)
      out << p.place << "," << p.first_frame << "," << p.last_frame << "," << p.representative_frame << ","
          << p.keypoints << "," << node_of_place[p.place] << "\n";
    out.commit();
  }
  {
    OutputFile out = openOutput(dir / "topology.json");
    JsonWriter json(out);
    json.beginObject();
    json.field("probability", run.topology ? run.topology->probability : 0.0);
    json.field("particles", run.topology ? run.topology->particles : 0);
    json.key("nodes").beginArray();
    if (run.topology)
      for (const TopologyNode& t : run.topology->nodes) {
        json.beginObject().field("id", t.id).key("places").beginArray();
        for (int p : t.places) json.value(p);
        json.endArray().key("representative_frames").beginArray();
        for (std::int64_t f : t.representative_frames) json.value(f);
        json.endArray().endObject();
      }
    json.endArray().key("edges").beginArray();
    if (run.topology)
      for (const TopologyEdge& e : run.topology->edges)
        json.beginObject().field("from", e.from).field("to", e.to).field("count", e.count).endObject();
    json.endArray().key("history").beginArray();
    for (const LoggedPlace& p : run.places)
      json.beginObject().field("place", p.place).field("node", p.node).field("probability", p.probability)
          .field("is_new", p.is_new).endObject();
    json.endArray().endObject();
    out << "\n";
    out.commit();
  }
  // The representatives' thumbnails, named as frames.csv names their frames: the report shows them.
  fs::create_directories(dir / "frames");
  for (const LoggedPlace& p : run.places) {
    if (p.thumbnail_jpeg.empty()) continue;
    OutputFile out = openOutput(dir / "frames" / frameName(p.representative_frame));
    out.write(reinterpret_cast<const char*>(p.thumbnail_jpeg.data()), static_cast<std::streamsize>(p.thumbnail_jpeg.size()));
    out.commit();
  }
  writeSettingsTxt(dir / "settings.txt", {{"source", "lcmlog:" + fs::absolute(log_path).string()},
                                          {"log events", std::to_string(run.events)},
                                          {"place estimates", std::to_string(run.frames.size())},
                                          {"place events", std::to_string(run.places.size())}});
}

}  // namespace toposlam::cli

// `toposlam map-info MAP [--json]`: what a map file (map.tsm, from `toposlam map` or toposlamd) holds:
// places, nodes, source, preset and settings, size, when it was saved.
// `toposlam export MAP --out DIR`: the map as a run folder that `toposlam report` and `toposlam eval` read
// (map_desk.hpp says what an export holds and what a map cannot give back).
#include <cstdio>
#include <iostream>
#include <memory>
#include <numeric>
#include <string>

#include "commands.hpp"
#include "map_desk.hpp"
#include "toposlam/core/json_writer.hpp"

namespace toposlam::cli {

namespace {

struct MapInfoOptions {
  std::string map;
  bool json = false;
};

struct ExportOptions {
  std::string map;
  std::string out;
};

std::int64_t frameCount(const DeskMap& map) {
  return std::accumulate(map.origins.run_frames.begin(), map.origins.run_frames.end(), std::int64_t{0});
}

std::string settingOr(const MapSettings& settings, const std::string& key, const std::string& otherwise) {
  const auto it = settings.find(key);
  return it == settings.end() || it->second.empty() ? otherwise : it->second;
}

void printMapInfoJson(const DeskMap& map) {
  JsonWriter json(std::cout);
  json.beginObject()
      .field("file", map.path.string())
      .field("bytes", static_cast<std::int64_t>(map.bytes))
      .field("saved", map.saved_utc)
      .field("written_by", writerName(map.origins.writer))
      .field("places", map.topology->observations())
      .field("nodes", nodeCount(map))
      .field("particles", map.topology->filter().config().particles)
      .field("best_topology_probability", map.estimate.best.probability)
      .field("current_node", map.estimate.current_node)
      .field("current_node_probability", map.estimate.current_node_probability)
      .field("source", settingOr(map.settings, kMapSourceKey, ""))
      .field("preset", presetOf(map.settings))
      .field("runs", map.origins.run_frames.size())
      .field("frames", frameCount(map));
  json.key("sources").beginArray();
  for (const MapTraversal& t : map.origins.traversals) json.value(t.source);
  json.endArray();
  json.key("settings").beginObject();
  for (const auto& [key, value] : map.settings) json.field(key, value);
  json.endObject().endObject();
  std::cout << "\n" << std::flush;
}

void printMapInfoText(const DeskMap& map) {
  std::printf("map            %s\n", map.path.string().c_str());
  std::printf("size           %llu bytes\n", static_cast<unsigned long long>(map.bytes));
  std::printf("saved          %s\n", map.saved_utc.c_str());
  std::printf("written by     %s\n", writerName(map.origins.writer));
  std::printf("places         %d\n", map.topology->observations());
  std::printf("nodes          %d\n", nodeCount(map));
  std::printf("current node   %d (p = %.3f)\n", map.estimate.current_node, map.estimate.current_node_probability);
  std::printf("best topology  p = %.3f over %d particles\n", map.estimate.best.probability,
              map.topology->filter().config().particles);
  std::printf("source         %s\n", settingOr(map.settings, kMapSourceKey, "(not recorded)").c_str());
  std::printf("preset         %s\n", presetOf(map.settings).c_str());
  if (!map.origins.run_frames.empty())
    std::printf("runs           %zu (%lld frames)\n", map.origins.run_frames.size(),
                static_cast<long long>(frameCount(map)));
  for (const MapTraversal& t : map.origins.traversals) std::printf("  run %d read   %s\n", t.run, t.source.c_str());
  std::printf("settings       %zu recorded:\n", map.settings.size());
  for (const auto& [key, value] : map.settings) std::printf("  %s = %s\n", key.c_str(), value.c_str());
}

void runMapInfo(const MapInfoOptions& o) {
  const DeskMap map = openDeskMap(o.map, "map-info");
  if (o.json)
    printMapInfoJson(map);
  else
    printMapInfoText(map);
}

void runExport(const ExportOptions& o) {
  const DeskMap map = openDeskMap(o.map, "export");
  writeExportedRun(map, o.out);
  std::cout << "exported " << o.map << " (" << map.topology->observations() << " places, " << nodeCount(map)
            << " nodes) into the run folder " << o.out << "\n";
}

}  // namespace

void addMapInfoCommand(CLI::App& app) {
  auto options = std::make_shared<MapInfoOptions>();
  auto* cmd = app.add_subcommand(
      "map-info", "What a map file holds: places, nodes, source, preset and settings, size, when it was saved");
  cmd->add_option("map", options->map, "Map file (map.tsm of `toposlam map` or toposlamd)")->required();
  cmd->add_flag("--json", options->json, "Print it as one JSON object");
  cmd->callback([options] { runMapInfo(*options); });
}

void addExportCommand(CLI::App& app) {
  auto options = std::make_shared<ExportOptions>();
  auto* cmd = app.add_subcommand(
      "export", "Write a map file as a run folder that `toposlam report` and `toposlam eval` read");
  cmd->add_option("map", options->map, "Map file (map.tsm of `toposlam map` or toposlamd)")->required();
  cmd->add_option("--out", options->out, "Output run folder")->required();
  cmd->callback([options] { runExport(*options); });
}

}  // namespace toposlam::cli

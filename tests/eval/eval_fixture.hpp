// Test helpers: a scratch folder under the build tree and a small hand-made run folder.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace toposlam::eval::testing {

inline std::filesystem::path scratchDir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(TOPOSLAM_BINARY_DIR) / "test-scratch" / "eval" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// A `map` run of 10 frames: places 0 (frames 0-2, node 0), 1 (3-5, node 1), 2 (6-9, node 0);
/// labels: rooms 0,0,0,-1,1,1,0,0,0,0 (room 1 behind a doorway frame, then back to room 0).
inline std::filesystem::path writeFixtureRun(const std::string& name) {
  const auto dir = scratchDir(name);
  writeText(
      dir / "frames.csv",
      "frame,time,name,lambda2,place,node\n"
      "0,0,a.png,,0,0\n1,1,b.png,,0,0\n2,2,c.png,0.9,0,0\n3,3,d.png,0.4,1,1\n4,4,e.png,0.8,1,1\n"
      "5,5,f.png,0.9,1,1\n6,6,g.png,0.3,2,0\n7,7,h.png,0.9,2,0\n8,8,i.png,0.9,2,0\n9,9,j.png,0.9,2,0\n");
  writeText(dir / "places.csv",
            "place,first,last,representative,keypoints,node\n0,0,2,1,50,0\n1,3,5,4,60,1\n2,6,9,7,70,0\n");
  writeText(dir / "dropped_places.csv", "place,first,last,representative,keypoints,node\n");
  writeText(dir / "topology.json",
            "{\"probability\": 0.7, \"particles\": 500,\n"
            " \"nodes\": [{\"id\": 0, \"places\": [0, 2], \"representative_frames\": [1, 7]},\n"
            "           {\"id\": 1, \"places\": [1], \"representative_frames\": [4]}],\n"
            " \"edges\": [{\"from\": 0, \"to\": 1, \"count\": 1}, {\"from\": 1, \"to\": 0, \"count\": 1}],\n"
            " \"history\": [{\"place\": 0, \"node\": 0, \"probability\": 1.0, \"best_topology_probability\": "
            "1.0, \"effective_sample_size\": 500},\n"
            "             {\"place\": 1, \"node\": 1, \"probability\": 0.95, \"best_topology_probability\": "
            "0.95, \"effective_sample_size\": 480},\n"
            "             {\"place\": 2, \"node\": 0, \"probability\": 0.6, \"best_topology_probability\": "
            "0.7, \"effective_sample_size\": 300}]}\n");
  writeText(dir / "timing.csv", "frame,fingerprint_ms,segment_ms,filter_ms\n0,10,1,0\n1,11,1,0\n2,12,2,5\n");
  writeText(dir / "labels.csv",
            "frame,time,room,x,y,heading\n0,0,0,0,0,0\n1,1,0,0,0,0\n2,2,0,0,0,0\n3,3,-1,0,0,0\n4,4,1,0,0,0\n"
            "5,5,1,0,0,0\n6,6,0,0,0,0\n7,7,0,0,0,0\n8,8,0,0,0,0\n9,9,0,0,0,0\n");
  return dir;
}

}  // namespace toposlam::eval::testing

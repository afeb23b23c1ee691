// The self-contained HTML report (see report.hpp). Layout decisions: one column, figures 1100 px wide,
// thumbnails 96 px wide; the topology is laid out on a circle in order of first visit (the order the
// robot found the nodes), so a loop traversed twice draws as a ring.
#include "toposlam/core/markup_escape.hpp"
#include "toposlam/eval/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>

#include "toposlam/core/svg_plot.hpp"

namespace toposlam::eval {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string num(double v, int decimals = 1) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, v);
  return buffer;
}

/// renderSvgLinePlot's document without the XML declaration, for inlining in HTML.
std::string inlineSvg(const SvgPlot& plot) {
  std::string svg = renderSvgLinePlot(plot);
  const auto start = svg.find("<svg");
  return start == std::string::npos ? svg : svg.substr(start);
}

bool hasNodes(const RunData& run) {
  return std::any_of(run.frames.begin(), run.frames.end(), [](const FrameRecord& f) { return f.node >= 0; });
}

/// Colour index of a frame: its node when the run has nodes, else its place.
int frameColourIndex(const RunData& run, std::size_t f, bool by_node) {
  return by_node ? run.frames[f].node : run.frames[f].place;
}

std::string stripSvg(const std::vector<int>& indices, const std::string& label, int width) {
  const std::size_t n = indices.size();
  std::ostringstream svg;
  const int label_width = 110, height = 26;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height << "\">";
  svg << "<text x=\"0\" y=\"17\" font-size=\"13\" font-family=\"sans-serif\">" << escapeMarkup(label)
      << "</text>";
  const double w = n > 0 ? static_cast<double>(width - label_width) / static_cast<double>(n) : 0.0;
  // Merge runs of one colour into one rectangle (a 3000-frame strip stays small).
  std::size_t start = 0;
  for (std::size_t f = 1; f <= n; ++f) {
    if (f < n && indices[f] == indices[start]) continue;
    svg << "<rect x=\"" << num(label_width + w * static_cast<double>(start), 2) << "\" y=\"2\" width=\""
        << num(w * static_cast<double>(f - start) + 0.3, 2) << "\" height=\"" << height - 4 << "\" fill=\""
        << indexColour(indices[start]) << "\"><title>frames " << start << "-" << f - 1 << ": "
        << indices[start] << "</title></rect>";
    start = f;
  }
  svg << "</svg>";
  return svg.str();
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
}

SvgPlot lambda2Plot(const ReportInputs& in) {
  const RunData& run = in.run;
  SvgPlot plot;
  plot.title = in.rooms.size() == run.frames.size() && !in.rooms.empty()
                   ? "lambda2 per frame; dashed red: place cuts; green: true room changes; grey: representatives; "
                     "blue: traversal starts"
                   : "lambda2 per frame; dashed red: place cuts; grey: representatives; blue: traversal starts";
  plot.x_label = "frame";
  plot.y_label = "lambda2";
  plot.width = 1160;
  SvgSeries s;
  s.label = "lambda2";
  for (const auto& f : run.frames) {
    s.x.push_back(static_cast<double>(f.frame));
    s.y.push_back(f.lambda2);
  }
  plot.series.push_back(s);
  const std::vector<std::int64_t> starts = in.eval ? in.eval->traversal_starts : run.traversal_starts;
  for (std::int64_t c : predictedCuts(run, starts)) {
    plot.vertical_lines.push_back(SvgLine{static_cast<double>(c) - 0.5, "#d62728", true, ""});
  }
  for (const auto& p : run.places)
    plot.vertical_lines.push_back(SvgLine{static_cast<double>(p.representative), "#bbbbbb", false, ""});
  if (in.rooms.size() == run.frames.size()) {
    // A room change: the first frame in a room other than the last room seen (doorway frames skipped).
    int last_room = -1;
    for (std::size_t f = 0; f < in.rooms.size(); ++f) {
      const int r = in.rooms[f];
      if (r < 0) continue;
      if (last_room >= 0 && r != last_room)
        plot.vertical_lines.push_back(SvgLine{static_cast<double>(f) - 0.5, "#2ca02c", false, ""});
      last_room = r;
    }
  }
  for (const auto& [key, value] : run.settings) {
    if (key != "segmentation.gamma") continue;
    char* end = nullptr;
    const double gamma = std::strtod(value.c_str(), &end);
    if (end != value.c_str()) plot.horizontal_lines.push_back(SvgLine{gamma, "#9467bd", true, "gamma"});
  }
  for (std::size_t t = 1; t < starts.size(); ++t) {
    std::string label = "traversal ";
    label += std::to_string(t + 1);
    plot.vertical_lines.push_back(SvgLine{static_cast<double>(starts[t]) - 0.5, "#1f3fb4", false, label});
  }
  return plot;
}

SvgPlot probabilityPlot(const RunData& run) {
  SvgPlot plot;
  plot.title = "best topology probability and the current node's probability";
  plot.x_label = "place (filter step)";
  plot.y_label = "probability";
  plot.width = 1160;
  plot.y_min = 0.0;
  plot.y_max = 1.05;
  SvgSeries best{"most probable topology", {}, {}, "#1f77b4", 2.0};
  SvgSeries node{"current node", {}, {}, "#ff7f0e", 1.2};
  if (run.topology) {
    for (const auto& s : run.topology->history) {
      best.x.push_back(s.place);
      best.y.push_back(s.best_topology_probability.value_or(0.0));
      node.x.push_back(s.place);
      node.y.push_back(s.probability);
    }
  }
  plot.series = {best, node};
  return plot;
}

SvgPlot timingPlot(const RunData& run) {
  SvgPlot plot;
  plot.title = "milliseconds per frame";
  plot.x_label = "frame";
  plot.y_label = "ms";
  plot.width = 1160;
  plot.y_min = 0.0;
  SvgSeries total{"total", {}, {}, "#222222", 1.5};
  SvgSeries fp{"fingerprint (VPACK)", {}, {}, "#1f77b4", 1.0};
  SvgSeries seg{"segmentation", {}, {}, "#2ca02c", 1.0};
  SvgSeries filt{"particle filter", {}, {}, "#d62728", 1.0};
  for (const auto& t : run.timing) {
    const double x = static_cast<double>(t.frame);
    total.x.push_back(x);
    total.y.push_back(t.fingerprint_ms + t.segment_ms + t.filter_ms.value_or(0.0));
    fp.x.push_back(x);
    fp.y.push_back(t.fingerprint_ms);
    seg.x.push_back(x);
    seg.y.push_back(t.segment_ms);
    filt.x.push_back(x);
    filt.y.push_back(t.filter_ms.value_or(0.0));
  }
  plot.series = {total, fp, seg, filt};
  return plot;
}

}  // namespace

SvgPlot precisionRecallPlot(const std::string& title, const std::vector<PrSeries>& curves) {
  SvgPlot plot;
  plot.title = title;
  plot.x_label = "recall";
  plot.y_label = "precision";
  plot.width = 600;
  plot.height = 360;
  plot.x_min = 0.0;
  plot.x_max = 1.0;
  plot.y_min = 0.0;
  plot.y_max = 1.05;
  for (const PrSeries& c : curves) {
    SvgSeries s{c.label, {}, {}, c.colour, 2.0};
    for (const auto& p : c.points) {
      s.x.push_back(p.recall);
      s.y.push_back(p.precision);
    }
    plot.series.push_back(std::move(s));
  }
  return plot;
}

std::string base64Encode(const std::vector<std::uint8_t>& bytes) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v =
        (static_cast<unsigned>(bytes[i]) << 16) | (static_cast<unsigned>(bytes[i + 1]) << 8) | bytes[i + 2];
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += alphabet[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = static_cast<unsigned>(bytes[i]) << 16;
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (static_cast<unsigned>(bytes[i]) << 16) | (static_cast<unsigned>(bytes[i + 1]) << 8);
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::string indexColour(int i) {
  if (i < 0) return "#bbbbbb";
  // Golden-angle hue steps keep neighbouring indices apart; two lightness levels double the distinct set.
  const double hue = std::fmod(static_cast<double>(i) * 137.508, 360.0);
  const int lightness = (i / 7) % 2 == 0 ? 50 : 38;
  std::ostringstream css;
  css << "hsl(" << num(hue, 0) << ",70%," << lightness << "%)";
  return css.str();
}

std::vector<std::int64_t> framesForThumbnails(const RunData& run, int strip_count) {
  std::set<std::int64_t> frames;
  const auto n = static_cast<std::int64_t>(run.frames.size());
  if (n > 0 && strip_count > 0) {
    const std::int64_t step = std::max<std::int64_t>(1, (n + strip_count - 1) / strip_count);
    for (std::int64_t f = 0; f < n; f += step) frames.insert(f);
  }
  for (const auto& p : run.places) {
    if (p.representative >= 0 && p.representative < n) frames.insert(p.representative);
  }
  if (run.topology) {
    for (const auto& node : run.topology->nodes) {
      for (std::int64_t f : node.representative_frames) {
        if (f >= 0 && f < n) frames.insert(f);
      }
    }
  }
  return {frames.begin(), frames.end()};
}

namespace {

// Place-pair loop closures and, when frames.csv has them, the frame-level detections.
SvgPlot loopClosurePlot(const EvalResult& eval) {
  std::vector<PrSeries> curves{{"frame pairs on one node (score: node probability)", eval.loop_closure->points, "#9467bd"}};
  if (eval.frame_loop_closure)
    curves.push_back({"frame level (score: frames.csv match_score)", eval.frame_loop_closure->curve, "#2ca02c"});
  return precisionRecallPlot("loop closure: precision vs. recall", curves);
}
/// The topology drawing: HTML (an SVG of the edges under absolutely positioned <div>s with <img>, so the
/// browser check sees every thumbnail) or one standalone SVG document (<image> elements).
std::string topologyMarkup(const RunData& run, const std::vector<std::string>& thumbnails, bool svg_only) {
  if (!run.topology || run.topology->nodes.empty())
    return "<p class=\"note\">No topology.json in this run folder.</p>\n";
  const TopologyFile& topo = *run.topology;
  // Order nodes by their first place (the order the robot discovered them).
  std::vector<const TopologyFile::Node*> nodes;
  for (const auto& node : topo.nodes) nodes.push_back(&node);
  auto first_place = [](const TopologyFile::Node* node) {
    return node->places.empty() ? 1 << 30 : *std::min_element(node->places.begin(), node->places.end());
  };
  std::stable_sort(nodes.begin(), nodes.end(),
                   [&](auto* a, auto* b) { return first_place(a) < first_place(b); });
  const auto count = static_cast<double>(nodes.size());
  const double thumb_w = 96, thumb_h = 72;
  const double radius = std::max(170.0, count * 200.0 / (2 * kPi));
  const double margin = 110;
  const double size = nodes.size() <= 1 ? 2 * margin + 40 : 2 * (radius + margin);
  std::map<int, std::pair<double, double>> position;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const double angle = -kPi / 2 + 2 * kPi * static_cast<double>(k) / count;
    const double r = nodes.size() <= 1 ? 0.0 : radius;
    position[nodes[k]->id] = {size / 2 + r * std::cos(angle), size / 2 + r * std::sin(angle)};
  }
  std::ostringstream html;
  if (!svg_only) {
    html << "<div class=\"topology\" style=\"position:relative;width:" << num(size, 0)
         << "px;height:" << num(size, 0) << "px\">\n";
  }
  html << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(size, 0) << "\" height=\""
       << num(size, 0)
       << "\" style=\"position:absolute;left:0;top:0;background:#fff\"><defs><marker id=\"arrow\" "
          "viewBox=\"0 0 10 10\" refX=\"10\" "
          "refY=\"5\" markerWidth=\"7\" markerHeight=\"7\" orient=\"auto-start-reverse\"><path d=\"M0,0 "
          "L10,5 L0,10 z\" "
          "fill=\"#444\"/></marker></defs>\n";
  std::set<std::pair<int, int>> edge_set;
  for (const auto& e : topo.edges) edge_set.insert({e.from, e.to});
  for (const auto& e : topo.edges) {
    if (!position.count(e.from) || !position.count(e.to)) continue;
    auto [x1, y1] = position[e.from];
    auto [x2, y2] = position[e.to];
    const double dx = x2 - x1, dy = y2 - y1, length = std::max(1.0, std::hypot(dx, dy));
    // Stop the arrow at the thumbnail's edge (an ellipse around the node centre).
    const double shrink = std::min(0.45, 62.0 / length);
    const double sx = x1 + dx * shrink, sy = y1 + dy * shrink, ex = x2 - dx * shrink, ey = y2 - dy * shrink;
    // Both directions present: bend each to its own side.
    const double bend = edge_set.count({e.to, e.from}) ? 28.0 : 0.0;
    const double cx = (sx + ex) / 2 - dy / length * bend, cy = (sy + ey) / 2 + dx / length * bend;
    html << "<path d=\"M" << num(sx) << "," << num(sy) << " Q" << num(cx) << "," << num(cy) << " " << num(ex)
         << "," << num(ey) << "\" fill=\"none\" stroke=\"#444\" stroke-width=\""
         << num(std::min(6.0, 1.0 + e.count * 0.8)) << "\" marker-end=\"url(#arrow)\"><title>node " << e.from
         << " -> " << e.to << ": " << e.count << " times</title></path>";
    if (e.count > 1) {
      html << "<text x=\"" << num(cx) << "\" y=\"" << num(cy)
           << "\" font-size=\"12\" font-family=\"sans-serif\" "
           << "fill=\"#222\">" << e.count << "</text>";
    }
    html << "\n";
  }
  if (!svg_only) html << "</svg>\n";
  for (const TopologyFile::Node* node : nodes) {
    const auto [x, y] = position[node->id];
    std::string thumb;
    for (std::int64_t f : node->representative_frames) {
      if (f >= 0 && static_cast<std::size_t>(f) < thumbnails.size() &&
          !thumbnails[static_cast<std::size_t>(f)].empty()) {
        thumb = thumbnails[static_cast<std::size_t>(f)];
        break;
      }
    }
    std::string places;
    for (std::size_t k = 0; k < node->places.size(); ++k) {
      if (k > 0) places += ',';
      places += std::to_string(node->places[k]);
    }
    if (svg_only) {
      const double left = x - thumb_w / 2, top = y - thumb_h / 2;
      html << "<rect x=\"" << num(left - 4) << "\" y=\"" << num(top - 4) << "\" width=\"" << num(thumb_w + 8)
           << "\" height=\"" << num(thumb_h + 36) << "\" rx=\"6\" fill=\"#fff\" stroke=\""
           << indexColour(node->id) << "\" stroke-width=\"4\"/>";
      if (!thumb.empty()) {
        html << "<image x=\"" << num(left) << "\" y=\"" << num(top) << "\" width=\"" << thumb_w
             << "\" height=\"" << thumb_h << "\" preserveAspectRatio=\"xMidYMid slice\" href=\"" << thumb
             << "\"/>";
      }
      html << "<text x=\"" << num(x) << "\" y=\"" << num(top + thumb_h + 13) << "\" font-size=\"11\" "
           << "font-family=\"sans-serif\" text-anchor=\"middle\">node " << node->id << "</text><text x=\""
           << num(x) << "\" y=\"" << num(top + thumb_h + 26)
           << "\" font-size=\"11\" font-family=\"sans-serif\" "
           << "text-anchor=\"middle\">places " << escapeMarkup(places) << "</text>\n";
      continue;
    }
    html << "<div class=\"node\" style=\"left:" << num(x - thumb_w / 2 - 4, 0)
         << "px;top:" << num(y - thumb_h / 2 - 4, 0) << "px;border-color:" << indexColour(node->id) << "\">";
    if (!thumb.empty()) {
      html << "<img src=\"" << thumb << "\" width=\"" << thumb_w << "\" height=\"" << thumb_h
           << "\" alt=\"node " << node->id << "\">";
    } else {
      html << "<div class=\"nothumb\" style=\"width:" << thumb_w << "px;height:" << thumb_h
           << "px\">no frame</div>";
    }
    html << "<div class=\"label\">node " << node->id << "<br>places " << escapeMarkup(places)
         << "</div></div>\n";
  }
  html << (svg_only ? "</svg>\n" : "</div>\n");
  return html.str();
}
}  // namespace

std::string renderTopologyHtml(const RunData& run, const std::vector<std::string>& thumbnails) {
  return topologyMarkup(run, thumbnails, false);
}

std::map<std::string, std::string> renderReportFigures(const ReportInputs& in) {
  std::map<std::string, std::string> figures;
  const RunData& run = in.run;
  const bool by_node = hasNodes(run);
  std::vector<int> colour(run.frames.size());
  for (std::size_t f = 0; f < colour.size(); ++f) colour[f] = frameColourIndex(run, f, by_node);
  std::string strip = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  strip += stripSvg(colour, by_node ? "node" : "place", 1160);
  figures["strip.svg"] = strip;
  if (in.rooms.size() == run.frames.size() && !in.rooms.empty()) {
    std::string rooms = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    rooms += stripSvg(in.rooms, "true room", 1160);
    figures["rooms.svg"] = rooms;
  }
  figures["lambda2.svg"] = renderSvgLinePlot(lambda2Plot(in));
  if (run.topology && !run.topology->nodes.empty()) {
    figures["topology.svg"] = topologyMarkup(run, in.thumbnails, true);
    figures["probability.svg"] = renderSvgLinePlot(probabilityPlot(run));
  }
  if (!run.timing.empty()) figures["timing.svg"] = renderSvgLinePlot(timingPlot(run));
  if (in.eval && in.eval->loop_closure && !in.eval->loop_closure->points.empty()) {
    figures["precision_recall.svg"] = renderSvgLinePlot(loopClosurePlot(*in.eval));
  }
  return figures;
}

namespace {

// The page's sections, in order. Each writes its markup to `html`.

void writeHead(std::ostream& html, const std::string& title) {
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << escapeMarkup(title)
       << "</title>\n<style>\n"
          "body{font-family:sans-serif;margin:20px;max-width:1200px;color:#222}\n"
          "h2{border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:32px}\n"
          ".thumbs{display:flex;flex-wrap:wrap;gap:4px}\n"
          ".thumbs figure{margin:0;border:4px solid;font-size:10px;text-align:center;background:#f6f6f6}\n"
          ".thumbs img{display:block;width:96px;height:72px;object-fit:cover}\n"
          ".topology .node{position:absolute;border:4px "
          "solid;background:#fff;font-size:11px;text-align:center;"
          "border-radius:6px}\n"
          ".topology .node img{display:block;object-fit:cover}\n"
          ".nothumb{background:#eee;color:#888;line-height:72px}\n"
          "table.eval{border-collapse:collapse;margin:12px 0}\n"
          "h3.eval{font-size:15px;margin:18px 0 4px 0}\n"
          "table.eval td,table.eval th{border:1px solid #ccc;padding:3px 10px;text-align:right}\n"
          ".note{color:#a33}\n.legend span{display:inline-block;width:12px;height:12px;margin:0 4px 0 12px}\n"
          "</style></head><body>\n";
  html << "<h1>" << escapeMarkup(title) << "</h1>\n";
}

/// What the run was made from and with, and what made this page.
void writeRunTable(std::ostream& html, const ReportInputs& in) {
  const RunData& run = in.run;
  html << "<table class=\"eval\"><caption>Run</caption>\n";
  const auto row = [&](const std::string& key, const std::string& value) {
    html << "<tr><th style=\"text-align:left\">" << escapeMarkup(key) << "</th><td style=\"text-align:left\">"
         << escapeMarkup(value) << "</td></tr>\n";
  };
  for (std::size_t k = 0; k < run.sources.size(); ++k)
    row(run.sources.size() == 1 ? "source" : "source " + std::to_string(k + 1), run.sources[k]);
  if (run.sources.empty()) row("source", "not recorded (no source.txt in the run folder)");
  for (const auto& [key, value] : run.settings) row(key == "toposlam" ? "made by toposlam" : key, value);
  if (run.settings.empty()) row("settings", "not recorded (no settings.txt: a run of `segment` or an older `map`)");
  if (!in.generator.empty()) row("report by", in.generator);
  if (!in.generated.empty()) row("report made", in.generated);
  html << "</table>\n";
}

/// Counts of frames, places and nodes, and the warnings of the inputs.
void writeSummary(std::ostream& html, const ReportInputs& in) {
  const RunData& run = in.run;
  int nodes = 0;
  double best_p = std::nan("");
  if (run.topology) {
    nodes = static_cast<int>(run.topology->nodes.size());
    best_p = run.topology->probability;
  }
  html << "<p>" << run.frames.size() << " frames, " << run.places.size() << " places (" << run.dropped_places.size()
       << " dropped)";
  if (run.topology)
    html << ", " << nodes << " nodes in the most probable topology (p = " << num(best_p, 3) << ")";
  html << ". Run folder <code>" << escapeMarkup(run.dir) << "</code>.</p>\n";
  for (const auto& w : in.warnings) html << "<p class=\"note\">" << escapeMarkup(w) << "</p>\n";
}

/// Section 1's strips: frames coloured by node (or place), and by true room when known, with its legend.
void writeStrips(std::ostream& html, const ReportInputs& in, const std::vector<int>& colour, bool by_node) {
  const std::size_t n = in.run.frames.size();
  html << "<h2>Frames coloured by " << (by_node ? "node" : "place") << "</h2>\n";
  html << "<div>" << stripSvg(colour, by_node ? "node" : "place", 1160) << "</div>\n";
  if (in.rooms.size() == n && n > 0) {
    html << "<div>" << stripSvg(in.rooms, "true room", 1160) << "</div>\n";
    std::set<int> room_ids(in.rooms.begin(), in.rooms.end());
    html << "<p class=\"legend\">true rooms:";
    for (int r : room_ids) html << "<span style=\"background:" << indexColour(r) << "\"></span>" << (r < 0 ? std::string("doorway") : "room " + std::to_string(r));
    html << "</p>\n";
    html << "<p>Colours of the two strips are independent (node ids and room ids are different numbers); "
            "grey = no place / doorway. Which node stands for which room: the table below.</p>\n";
  }
}

/// Section 1's legend: every node (or place) colour, with the room most of its frames are in when rooms
/// are known, and then the frames per node and room.
void writeColourLegend(std::ostream& html, const ReportInputs& in, const std::vector<int>& colour, bool by_node) {
  const std::size_t n = in.run.frames.size();
  std::map<int, std::map<int, int>> rooms_of;  // colour index -> room -> frames
  for (std::size_t f = 0; f < n; ++f) {
    if (colour[f] < 0) continue;
    rooms_of[colour[f]][in.rooms.size() == n ? in.rooms[f] : -2] += 1;
  }
  html << "<p class=\"legend\">";
  for (const auto& [index, rooms] : rooms_of) {
    int best_room = -2, best = 0, total = 0;
    for (const auto& [room, count] : rooms) {
      total += count;
      if (room >= 0 && count > best) best = count, best_room = room;
    }
    html << "<span style=\"background:" << indexColour(index) << "\"></span>" << (by_node ? "node " : "place ")
         << index;
    if (best_room >= 0) html << " (room " << best_room << ", " << num(100.0 * best / total, 0) << " %)";
  }
  html << "</p>\n";
  if (by_node && in.rooms.size() == n && n > 0) {
    // Confusion matrix: frames of each node in each room.
    std::set<int> room_ids;
    for (int r : in.rooms) room_ids.insert(r);
    html << "<table class=\"eval\"><caption>Frames per node (rows) and true room (columns; -1 = doorway); "
            "the largest cell of each row in bold</caption>\n<tr><th>node</th>";
    for (int r : room_ids) html << "<th>" << r << "</th>";
    html << "</tr>\n";
    for (const auto& [node, rooms] : rooms_of) {
      int best = 0;
      for (const auto& [room, count] : rooms)
        if (room >= 0) best = std::max(best, count);
      html << "<tr><th><span style=\"display:inline-block;width:10px;height:10px;background:" << indexColour(node)
           << "\"></span> " << node << "</th>";
      for (int r : room_ids) {
        const auto it = rooms.find(r);
        const int count = it == rooms.end() ? 0 : it->second;
        html << "<td>" << (count > 0 && count == best && r >= 0 ? "<b>" : "") << (count > 0 ? std::to_string(count) : "")
             << (count > 0 && count == best && r >= 0 ? "</b>" : "") << "</td>";
      }
      html << "</tr>\n";
    }
    html << "</table>\n";
  }
}

/// Section 1's thumbnails: about 96 frames evenly spread, bordered in their node (or place) colour.
void writeThumbnailGrid(std::ostream& html, const ReportInputs& in, const std::vector<int>& colour, bool by_node) {
  const std::size_t n = in.run.frames.size();
  std::vector<std::int64_t> strip_frames;
  const std::int64_t step = std::max<std::int64_t>(1, (static_cast<std::int64_t>(n) + 95) / 96);
  for (std::int64_t f = 0; f < static_cast<std::int64_t>(n); f += step) strip_frames.push_back(f);
  bool any = false;
  std::ostringstream grid;
  grid << "<div class=\"thumbs\">\n";
  for (std::int64_t f : strip_frames) {
    const auto fi = static_cast<std::size_t>(f);
    if (fi >= in.thumbnails.size() || in.thumbnails[fi].empty()) continue;
    any = true;
    const int c = colour[fi];
    grid << "<figure style=\"border-color:" << indexColour(c) << "\"><img src=\"" << in.thumbnails[fi]
         << "\" alt=\"frame " << f << "\"><figcaption>" << f << (by_node ? " · n" : " · p") << c
         << "</figcaption></figure>\n";
  }
  grid << "</div>\n";
  if (any) {
    html << "<p>Every " << step << (step == 1 ? "st" : "th") << " frame; the border is the frame's "
         << (by_node ? "node" : "place") << " colour.</p>\n"
         << grid.str();
  }
}

/// Section 2: lambda2 over time, then the places with their representatives.
void writeLambda2AndPlaces(std::ostream& html, const ReportInputs& in) {
  const RunData& run = in.run;
  const std::size_t n = run.frames.size();
  html << "<h2>Fiedler value lambda2 over time with the place cuts (thesis Figure 4.10)</h2>\n";
  html << "<div>" << inlineSvg(lambda2Plot(in)) << "</div>\n";
  if (run.places.empty()) return;
  html << "<h2>Places and their representatives</h2>\n<table class=\"eval\"><tr><th>place</th><th>frames</th>"
          "<th>representative</th><th>node</th><th>ended by</th>"
       << (in.rooms.size() == n ? "<th>true room (share of its frames)</th>" : "") << "</tr>\n";
  for (const auto& p : run.places) {
    html << "<tr><td>" << p.place << "</td><td>" << p.first << "-" << p.last << "</td><td>";
    const auto rep = static_cast<std::size_t>(p.representative);
    if (rep < in.thumbnails.size() && !in.thumbnails[rep].empty())
      html << "<img src=\"" << in.thumbnails[rep] << "\" alt=\"frame " << p.representative
           << "\" style=\"width:96px;height:72px;object-fit:cover;vertical-align:middle\"> ";
    html << p.representative << "</td><td>" << (p.node >= 0 ? std::to_string(p.node) : "-") << "</td><td>"
         << (p.end.empty() ? std::string("-") : escapeMarkup(p.end)) << "</td>";
    if (in.rooms.size() == n) {
      const std::vector<int> rooms(in.rooms.begin() + p.first, in.rooms.begin() + p.last + 1);
      const int room = majority(rooms);
      const auto share = static_cast<double>(std::count(rooms.begin(), rooms.end(), room)) / rooms.size();
      html << "<td>" << (room >= 0 ? std::to_string(room) + " (" + num(100.0 * share, 0) + " %)" : std::string("-"))
           << "</td>";
    }
    html << "</tr>\n";
  }
  html << "</table>\n";
}

/// Sections 3 and 4: the most probable topology, and its probability after each place.
void writeTopology(std::ostream& html, const ReportInputs& in) {
  const RunData& run = in.run;
  html << "<h2>Most probable topology (thesis Figure 5.4)</h2>\n";
  html << "<p>Each node shows the frame of its first representative; arrows are transitions between "
          "consecutive "
          "places (number = times traversed). Nodes are placed clockwise in the order they were "
          "discovered.</p>\n";
  html << renderTopologyHtml(run, in.thumbnails);
  if (run.topology && !run.topology->history.empty()) {
    html << "<h2>Probability of the most probable topology after each place</h2>\n";
    html << "<div>" << inlineSvg(probabilityPlot(run)) << "</div>\n";
  }
}

/// Section 5: processing time per frame, plotted and summarised per stage.
void writeTiming(std::ostream& html, const RunData& run) {
  if (run.timing.empty()) return;
  html << "<h2>Processing time per frame (thesis Figures 5.6/5.7)</h2>\n";
  std::vector<double> t_total, t_fp, t_seg, t_filt;
  for (const auto& t : run.timing) {
    t_total.push_back(t.fingerprint_ms + t.segment_ms + t.filter_ms.value_or(0.0));
    t_fp.push_back(t.fingerprint_ms);
    t_seg.push_back(t.segment_ms);
    t_filt.push_back(t.filter_ms.value_or(0.0));
  }
  html << "<div>" << inlineSvg(timingPlot(run)) << "</div>\n";
  html << "<table class=\"eval\"><caption>Time per frame, "
          "ms</caption><tr><th>stage</th><th>mean</th><th>median</th>"
          "<th>p99</th><th>max</th></tr>\n";
  auto row = [&](const char* name, const std::vector<double>& v) {
    double mean = 0;
    for (double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    html << "<tr><td>" << name << "</td><td>" << num(mean) << "</td><td>" << num(percentile(v, 0.5))
         << "</td><td>" << num(percentile(v, 0.99)) << "</td><td>"
         << num(*std::max_element(v.begin(), v.end())) << "</td></tr>\n";
  };
  row("fingerprint", t_fp);
  row("segmentation", t_seg);
  row("particle filter", t_filt);
  row("total", t_total);
  html << "</table>\n";
}

/// Section 6: the evaluation against ground truth, or how to give one.
void writeEvaluation(std::ostream& html, const ReportInputs& in) {
  html << "<h2>Evaluation against ground truth</h2>\n";
  if (!in.eval) {
    html << "<p>No ground truth given (<code>--truth labels.csv | GT.bmp | pairs.csv</code>).</p>\n";
    return;
  }
  html << "<p>Ground truth: <code>" << escapeMarkup(in.eval->truth_path) << "</code> (" << in.eval->truth_kind
       << ").</p>\n";
  html << formatEvalHtml(*in.eval);
  if (in.eval->boundaries && !(in.eval->boundaries->f1 >= 0.5)) {
    const BoundaryScore& b = *in.eval->boundaries;
    html << "<p class=\"note\">Why the segmentation score is low: a cut counts only within " << b.tolerance
         << " frames of the frame where the robot's position changes room. A forward camera sees the next "
            "room through the doorway before it crosses it, and the corridor only after turning into it, so "
            "appearance changes (and cuts) fall some frames before entering and after leaving"
         << (std::isfinite(b.mean_offset) ? " (matched cuts: " + num(b.mean_offset, 1) + " frames on average)" : std::string())
         << ". The place revisits judged by pose, above, score the places themselves.</p>\n";
  }
  if (in.eval->loop_closure && !in.eval->loop_closure->points.empty()) {
    html << "<div>" << inlineSvg(loopClosurePlot(*in.eval)) << "</div>\n";
  }
}

/// The simulated world's pictures (from `toposlam sim`), when given.
void writePictures(std::ostream& html, const ReportInputs& in) {
  if (in.pictures.empty()) return;
  html << "<h2>The simulated world</h2>\n";
  for (const auto& [caption, uri] : in.pictures)
    html << "<figure style=\"display:inline-block;margin:0 12px 12px 0\"><img src=\"" << uri << "\" alt=\""
         << escapeMarkup(caption) << "\" style=\"max-width:560px\"><figcaption>" << escapeMarkup(caption)
         << "</figcaption></figure>\n";
}

/// The page's own image check, for the browser test: kept in the page, not shown.
void writeImageCheckAndEnd(std::ostream& html) {
  html << "<p id=\"image-check\" hidden>images-pending</p>\n"
          "<script>\nwindow.addEventListener('load', function () {\n"
          "  var images = Array.prototype.slice.call(document.images);\n"
          "  var missing = images.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });\n"
          "  document.getElementById('image-check').textContent =\n"
          "      missing.length ? 'images-missing ' + missing.length : 'images-ok ' + images.length;\n"
          "});\n</script>\n</body></html>\n";
}

}  // namespace

std::string renderReportHtml(const ReportInputs& in) {
  const RunData& run = in.run;
  const bool by_node = hasNodes(run);
  std::vector<int> colour(run.frames.size());
  for (std::size_t f = 0; f < colour.size(); ++f) colour[f] = frameColourIndex(run, f, by_node);
  std::ostringstream html;
  writeHead(html, in.title);
  writeRunTable(html, in);
  writeSummary(html, in);
  writeStrips(html, in, colour, by_node);
  writeColourLegend(html, in, colour, by_node);
  writeThumbnailGrid(html, in, colour, by_node);
  writeLambda2AndPlaces(html, in);
  writeTopology(html, in);
  writeTiming(html, run);
  writeEvaluation(html, in);
  writePictures(html, in);
  writeImageCheckAndEnd(html);
  return html.str();
}

}  // namespace toposlam::eval

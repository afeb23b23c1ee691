// Reading and writing a config against its key table, for every program's table: see config_reader.hpp.
#include "toposlam/config/config_reader.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>
#include <yaml-cpp/yaml.h>

namespace toposlam {

namespace {

std::string describeNode(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

std::string lineOf(const YAML::Node& node) { return "line " + std::to_string(node.Mark().line + 1); }

std::string joinPath(const std::string& section, const std::string& key) {
  return section.empty() ? key : section + "." + key;
}

// `node` as a value of `key`'s kind; ConfigError "<path>: expected ..." if it is not one. Ranges are not
// checked here.
ConfigValue valueOf(const ConfigKeySpec& key, const YAML::Node& node) {
  const std::string& path = key.path;
  switch (key.kind) {
    case ConfigKind::Integer:
      // YAML 1.1 (yaml-cpp) reads 010 as octal 8, YAML 1.2 as decimal 10: neither is said, so refused.
      if (node.IsScalar()) {
        const std::string& text = node.Scalar();
        const std::size_t digits = text.find_first_not_of("+-");
        if (digits != std::string::npos && text.size() > digits + 1 && text[digits] == '0' &&
            text.find_first_not_of("0123456789", digits) == std::string::npos)
          throw ConfigError(path + ": '" + text +
                            "' has a leading zero (read as octal by some YAML readers, as "
                            "decimal by others); write it without");
      }
      try {
        return node.as<long long>();
      } catch (const YAML::Exception&) {
        throw ConfigError(path + ": expected an integer in " + key.rangeText() + ", got " +
                          describeNode(node));
      }
    case ConfigKind::Real:
      try {
        return node.as<double>();
      } catch (const YAML::Exception&) {
        throw ConfigError(path + ": expected a number in " + key.rangeText() + ", got " + describeNode(node));
      }
    case ConfigKind::Flag:
      try {
        return node.as<bool>();
      } catch (const YAML::Exception&) {
        throw ConfigError(path + ": expected true or false, got " + describeNode(node));
      }
    case ConfigKind::Text:
      if (!node.IsScalar()) throw ConfigError(path + ": expected a string, got " + describeNode(node));
      return node.Scalar();
    case ConfigKind::Choice:
      if (!node.IsScalar())
        throw ConfigError(path + ": " + describeNode(node) + " is not allowed, expected " + key.rangeText());
      return node.Scalar();
  }
  throw ConfigError(path + ": unknown kind of key");
}

// Reads one key's value: refused when it has none, is of the wrong kind or out of range (checked before
// it is stored, so a too large integer is never narrowed into the member).
ConfigValue readValue(const ConfigKeySpec& key, const YAML::Node& node) {
  if (node.IsNull()) throw ConfigError(key.path + ": has no value (remove the key to keep the default)");
  if (node.IsMap()) throw ConfigError(key.path + ": expected a value, got a mapping");
  const ConfigValue value = valueOf(key, node);
  if (std::string problem = key.problem(value); !problem.empty())
    throw ConfigError(key.path + ": " + problem);
  return value;
}

// A key table seen as a tree: the keys and the sections (mappings) at each path.
struct KeyTree {
  std::map<std::string, std::size_t> keys;                // full path -> index in the table
  std::map<std::string, std::set<std::string>> children;  // section path ("" = top level) -> child names

  explicit KeyTree(const std::vector<const ConfigKeySpec*>& table) {
    for (std::size_t i = 0; i < table.size(); ++i) {
      const std::string& path = table[i]->path;
      keys[path] = i;
      std::string section;
      std::size_t begin = 0;
      for (std::size_t dot = path.find('.');; dot = path.find('.', begin)) {
        const std::string name =
            path.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin);
        children[section].insert(name);
        if (dot == std::string::npos) break;
        section = joinPath(section, name);
        begin = dot + 1;
      }
    }
  }
  bool isSection(const std::string& path) const { return children.count(path) > 0; }
};

struct TreeReader {
  const std::vector<const ConfigKeySpec*>& table;
  const KeyTree& tree;
  const std::function<void(std::size_t, const ConfigValue&)>& set;
  const std::string& first;  // read before the walk: skipped in it

  // Reads the mapping at `section` ("" = the document): every entry must be a key of the table or a
  // section holding some; anything else is refused with its path and line.
  void readSection(const YAML::Node& node, const std::string& section) const {
    if (!node.IsDefined() || node.IsNull()) return;
    if (!node.IsMap())
      throw ConfigError((section.empty() ? std::string("top level") : section) +
                        ": expected a mapping of keys, got " + describeNode(node));
    for (const auto& entry : node) {
      const std::string name = entry.first.IsScalar() ? entry.first.Scalar() : describeNode(entry.first);
      const std::string path = joinPath(section, name);
      if (!first.empty() && path == first) continue;  // read first, by readConfigYaml
      if (auto key = tree.keys.find(path); key != tree.keys.end()) {
        set(key->second, readValue(*table[key->second], entry.second));
      } else if (tree.isSection(path)) {
        readSection(entry.second, path);
      } else {
        std::string known;
        for (const std::string& k : tree.children.at(section)) known += (known.empty() ? "" : ", ") + k;
        throw ConfigError("unknown key '" + path + "' (" + lineOf(entry.first) + "; known keys" +
                          (section.empty() ? "" : " under '" + section + "'") + ": " + known + ")");
      }
    }
  }
};

// Documents in a YAML text: a "---" line (marker alone or followed by a space) after content, or content
// after a "..." end line, starts another one. A leading "---" is the first document's optional marker.
int yamlDocumentCount(const std::string& text) {
  int documents = 0;
  bool content = false;  // the current document has a non-comment line
  bool ended = false;    // a "..." line closed it
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const bool start = line.rfind("---", 0) == 0 && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
    const bool end = line.rfind("...", 0) == 0 && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
    const std::size_t first = line.find_first_not_of(" \t");
    const bool blank = first == std::string::npos || line[first] == '#';
    if (start) {
      if (content || ended || documents == 0) ++documents;
      content = line.find_first_not_of(" \t", 3) != std::string::npos &&
                line[line.find_first_not_of(" \t", 3)] != '#';
      ended = false;
    } else if (end) {
      ended = true;
    } else if (!blank) {
      if (ended || documents == 0) ++documents;
      ended = false;
      content = true;
    }
  }
  return documents;
}

// Aliases (*name) are refused before the document is built: a config needs none, and yaml-cpp expands
// them into shared nodes that a walk over the tree visits once per path, so a 1 KB "billion laughs" file
// took minutes (issue 41). yaml-cpp's event parser reports each alias without expanding anything.
class AliasRefuser final : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
    if (first_alias_line < 0) first_alias_line = mark.line + 1;  // noted, not thrown through yaml-cpp
  }
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
  }
  void OnMapEnd() override {}
  int first_alias_line = -1;
};

void refuseAliases(const std::string& yaml_text) {
  std::istringstream in(yaml_text);
  YAML::Parser parser(in);
  AliasRefuser refuser;
  parser.HandleNextDocument(refuser);
  if (refuser.first_alias_line > 0)
    throw ConfigError("line " + std::to_string(refuser.first_alias_line) +
                      ": aliases (*name) are not allowed; write the value out");
}

// yaml-cpp keeps both entries of a repeated key and look-ups see only the first, so the second would be
// ignored silently: refused, naming the key and its line.
void refuseDuplicateKeys(const YAML::Node& node, const std::string& path) {
  if (node.IsSequence()) {
    for (const YAML::Node& item : node) refuseDuplicateKeys(item, path);
    return;
  }
  if (!node.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& entry : node) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
    const std::string full = path.empty() ? key : path + "." + key;
    if (!seen.insert(key).second)
      throw ConfigError("duplicate key '" + full + "' (line " + std::to_string(entry.first.Mark().line + 1) +
                        "); give each key once");
    refuseDuplicateKeys(entry.second, full);
  }
}

constexpr std::size_t kLineWidth = 110;

// The section part of a key path ("a.b" of "a.b.c"; "" at the top level).
std::string sectionOf(const std::string& path) {
  const std::size_t dot = path.rfind('.');
  return dot == std::string::npos ? "" : path.substr(0, dot);
}

std::vector<std::string> split(const std::string& path) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  for (std::size_t dot; (dot = path.find('.', begin)) != std::string::npos; begin = dot + 1)
    parts.push_back(path.substr(begin, dot - begin));
  if (!path.empty()) parts.push_back(path.substr(begin));
  return parts;
}

}  // namespace

void readConfigYaml(const std::string& text, const std::string& origin,
                    const std::vector<const ConfigKeySpec*>& keys,
                    const std::function<void(std::size_t, const ConfigValue&)>& set,
                    const ConfigReadOrder& order) {
  YAML::Node root;
  try {
    // A second document ("---") would be ignored silently by YAML::Load: refused instead. Found by
    // scanning the lines, not with YAML::LoadAll, which loops forever on some malformed input in
    // yaml-cpp 0.7 (found by fuzz_config; tests/fuzz/corpus/config/loadall-hang).
    if (const int documents = yamlDocumentCount(text); documents > 1)
      throw ConfigError(origin + ": holds " + std::to_string(documents) +
                        " YAML documents (a '---' line starts another); a config is exactly one");
    refuseAliases(text);
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ": not valid YAML: " + e.what());
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  const KeyTree tree(keys);
  try {
    refuseDuplicateKeys(root, "");
    // The first key, wherever it is written: it gives the other keys' defaults, which the text then
    // overrides.
    if (!order.first.empty() && !order.skip_first && root.IsMap()) {
      const YAML::Node& map = root;  // const look-up: the non-const operator[] would insert the key
      if (const YAML::Node node = map[order.first]; node.IsDefined()) {
        const std::size_t index = tree.keys.at(order.first);
        set(index, readValue(*keys[index], node));
      }
    }
    TreeReader{keys, tree, set, order.first}.readSection(root, "");
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw ConfigError(origin + ": " + e.what());
  }
}

std::string readConfigFile(const std::string& path, const std::string& file_name) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw ConfigError("the config file '" + path + "' is a folder; give the YAML file in it (e.g. " +
                      (std::filesystem::path(path) / file_name).string() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw ConfigError("cannot read the config file '" + path + "' (does it exist and is it readable?)");
  // Read at most the cap (+1 to notice more): /dev/zero or a runaway file never reads forever.
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw ConfigError("cannot read the config file '" + path + "'");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxConfigBytes)
    throw ConfigError("the config file '" + path + "' is larger than " +
                      std::to_string(kMaxConfigBytes >> 10) + " KiB; is it really a " + file_name + "?");
  return text;
}

ConfigValue configValueFromText(const ConfigKeySpec& key, const std::string& text) {
  const ConfigValue value = valueOf(key, YAML::Node(text));
  if (std::string problem = key.problem(value); !problem.empty())
    throw ConfigError(key.path + ": " + problem);
  return value;
}

bool isConfigSection(const std::vector<const ConfigKeySpec*>& keys, const std::string& path) {
  for (const ConfigKeySpec* key : keys)
    if (key->path.rfind(path + ".", 0) == 0) return true;
  return false;
}

ConfigOverride parseSetAssignment(const std::vector<const ConfigKeySpec*>& keys,
                                  const std::string& assignment, const std::string& example,
                                  const std::string& keys_listed) {
  const std::size_t equals = assignment.find('=');
  if (equals == std::string::npos || equals == 0)
    throw ConfigError("command line: --set " + assignment + ": expected KEY=VALUE, e.g. --set " + example);
  ConfigOverride o{assignment.substr(0, equals), assignment.substr(equals + 1), "--set " + assignment};
  bool known = false;
  for (const ConfigKeySpec* key : keys) known = known || key->path == o.path;
  if (!known) {
    std::string hint;
    if (isConfigSection(keys, o.path)) hint = " ('" + o.path + "' is a section; name one of its keys)";
    throw ConfigError("command line: --set " + assignment + ": unknown key '" + o.path + "'" + hint +
                      " (the keys: " + keys_listed + ")");
  }
  return o;
}

std::string configCommentLines(const std::string& prefix, const std::string& text) {
  std::string out, line = prefix;
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    if (line.size() > prefix.size() && line.size() + 1 + word.size() > kLineWidth) {
      out += line + "\n";
      line = prefix;
    }
    line += (line.size() > prefix.size() ? " " : "") + word;
  }
  return out + line + "\n";
}

std::string configKeyComment(const ConfigKeySpec& key) {
  std::string comment = key.help;
  if (key.kind != ConfigKind::Flag) comment += "; allowed " + key.rangeText();
  return comment;
}

std::string configYamlText(const std::vector<const ConfigKeySpec*>& keys,
                           const std::function<std::string(std::size_t)>& value_text,
                           const std::function<std::string(std::size_t)>& comment,
                           const std::function<std::string(const std::string&)>& section_help) {
  std::string out;
  std::vector<std::string> open;  // the sections the previous key was in
  std::set<std::string> explained;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const ConfigKeySpec& key = *keys[i];
    const std::vector<std::string> sections = split(sectionOf(key.path));
    std::size_t common = 0;
    while (common < open.size() && common < sections.size() && open[common] == sections[common]) ++common;
    open.resize(common);
    for (std::size_t depth = common; depth < sections.size(); ++depth) {
      const std::string indent(2 * depth, ' ');
      open.push_back(sections[depth]);
      std::string path;
      for (const std::string& s : open) path += (path.empty() ? "" : ".") + s;
      if (depth == 0) out += "\n";
      if (comment && section_help) {
        const std::string help = section_help(path);
        if (!help.empty()) out += configCommentLines(indent + "# ", help);
      }
      out += indent + sections[depth] + ":\n";
    }
    const std::string indent(2 * sections.size(), ' ');
    if (comment) {
      if (sections.empty()) out += "\n";
      // Keys of one name under sibling sections (the pipeline threads' five) are explained once.
      const std::string text = comment(i);
      const std::string grandparent = sectionOf(sectionOf(key.path));
      if (explained.insert(grandparent + "|" + split(key.path).back() + "|" + text).second)
        out += configCommentLines(indent + "# ", text);
    }
    out += indent + split(key.path).back() + ": " + value_text(i) + "\n";
  }
  return out;
}

}  // namespace toposlam

// The one translation unit that instantiates the X3 grammar: splits files into cards, parses
// each card with its rule, nests subcircuits and resolves includes.
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "netlist/grammar_def.hpp"
#include "netlist/lines.hpp"
#include "netlist/netlist.hpp"

namespace netlist {

namespace parser {

SourceRange CardContext::token_range(Iterator where) const {
  while (where != end() && (*where == ' ' || *where == '\t')) ++where;
  Iterator token_end = where;
  while (token_end != end() && *token_end != ' ' && *token_end != '\t') ++token_end;
  return range(where, token_end);
}

std::string CardContext::token(Iterator where) const {
  while (where != end() && (*where == ' ' || *where == '\t')) ++where;
  Iterator token_end = where;
  while (token_end != end() && *token_end != ' ' && *token_end != '\t') ++token_end;
  return std::string(where, token_end);
}

void CardContext::expected(Iterator where, const std::string& what) const {
  if (what == "end of card")
    diagnostics_.error(token_range(where), "unexpected " + quote(token(where)));
  else
    diagnostics_.error(token_range(where), "expected " + what);
}

}  // namespace parser

namespace {

// The file's text; null, with why in `why`, if it is not a readable regular file (devices and
// directories are refused so that an include cannot block or read forever).
std::shared_ptr<const SourceFile> read_source(const std::filesystem::path& path, std::string& why) {
  std::error_code error;
  const auto kind = std::filesystem::status(path, error).type();
  if (kind == std::filesystem::file_type::not_found) {
    why = "no such file";
    return nullptr;
  }
  if (kind != std::filesystem::file_type::regular) {
    why = error ? error.message() : "not a regular file";
    return nullptr;
  }
  std::ifstream stream(path, std::ios::binary);
  if (!stream) {
    why = std::strerror(errno);
    return nullptr;
  }
  std::ostringstream text;
  text << stream.rdbuf();
  return std::make_shared<const SourceFile>(path.string(), text.str());
}


using parser::CardContext;
using parser::Iterator;
namespace x3 = boost::spirit::x3;

// Parses a whole card with `rule`; false (with the error reported) when it does not parse.
template <typename Rule, typename Attribute>
bool parse_card_with(const Rule& rule, Attribute& attribute, const LogicalLine& line,
                     Diagnostics& diagnostics) {
  CardContext context(line, diagnostics);
  Iterator first = line.text.begin();
  int errors_before = diagnostics.error_count();
  bool parsed = false;
  try {
    auto const parser = x3::with<parser::card_context_tag>(std::ref(context))[rule];
    parsed = x3::phrase_parse(first, line.text.cend(), parser, x3::blank, attribute);
  } catch (const parser::CardError& error) {
    diagnostics.error(error.where, error.message);
    return false;
  }
  if (!parsed && diagnostics.error_count() == errors_before)
    context.expected(first, "a card");
  return parsed;
}

// Dot cards whose meaning padsim would change by ignoring them.
bool is_unsupported_directive(const std::string& directive) {
  static const char* const unsupported[] = {"func", "if", "elseif", "else", "endif",
                                            "step", "connect", "alter", "model_file"};
  for (const char* name : unsupported)
    if (directive == name) return true;
  return false;
}

std::string directive_of(const std::string& text) {
  std::string directive;
  for (std::size_t i = 1; i < text.size() && std::isalnum(static_cast<unsigned char>(text[i])); ++i)
    directive += static_cast<char>(std::tolower(static_cast<unsigned char>(text[i])));
  return directive;
}

// The blank-separated words of a card (for .lib section markers).
std::vector<std::string> words_of(const std::string& text) {
  std::istringstream stream(text);
  std::vector<std::string> words;
  for (std::string word; stream >> word;) words.push_back(word);
  return words;
}

// The words of a controlled source's card, lower case: what follows its two nodes tells its form.
std::vector<std::string> lower_case_words_of(const std::string& text) {
  std::vector<std::string> words = words_of(text);
  for (std::string& word : words)
    for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return words;
}

// E F G H with POLY(n) in place of their controls: "E1 out 0 POLY(2) a 0 b 0 0 1 1".
bool is_polynomial_card(const std::string& text) {
  const std::vector<std::string> words = lower_case_words_of(text);
  if (words.size() < 4) return false;
  const std::string& word = words[3];
  return word.starts_with("poly") &&
         (word.size() > 4 ? word[4] == '(' : words.size() > 4 && words[4].starts_with("("));
}

// E G with vol=, cur= or value= in place of their controls.
bool is_expression_card(const std::string& text) {
  const std::vector<std::string> words = lower_case_words_of(text);
  if (words.size() < 4) return false;
  const std::string& word = words[3];
  const std::string keyword = word.substr(0, word.find('='));
  return (keyword == "vol" || keyword == "cur" || keyword == "value") &&
         (keyword.size() < word.size() || (words.size() > 4 && words[4].starts_with("=")));
}

struct WaveformShape {
  const char* name;
  std::size_t min_args, max_args;
};

// ngspice's argument lists: pulse(v1 v2 td tr tf pw per np), sin(vo va freq td theta phase),
// exp(v1 v2 td1 tau1 td2 tau2), pwl(t1 v1 ...).
constexpr WaveformShape waveform_shapes[] = {
    {"pulse", 2, 8}, {"sin", 2, 6}, {"exp", 2, 6}, {"sffm", 2, 7}, {"pwl", 2, 1u << 30}};

class Parser {
 public:
  explicit Parser(Diagnostics& diagnostics) : diagnostics_(diagnostics) {}

  ast::Netlist parse_top(std::shared_ptr<const SourceFile> file) {
    ast::Netlist netlist;
    SplitFile split = split_lines(file, true, diagnostics_);
    netlist.title = split.title;
    netlist.title_where = split.title_where;
    include_stack_.push_back(file->path);
    netlist.cards = parse_cards(split, nullptr);
    include_stack_.pop_back();
    return netlist;
  }

 private:
  struct Section {
    std::string name;
    bool found = false;
  };

  // One parsed card: a card, an .ends (closing the innermost subcircuit), or nothing.
  struct Parsed {
    std::optional<ast::Card> card;
    bool opens_subcircuit = false;
    bool ends = false;
    std::optional<ast::Word> ends_name;
    SourceRange where;
  };

  std::vector<ast::Card> parse_cards(const SplitFile& split, Section* section) {
    std::vector<ast::Card> cards;
    std::vector<ast::Card> open;  // subcircuits being defined, innermost last
    bool in_wanted_section = false;
    for (const LogicalLine& line : split.cards) {
      if (section) {
        std::string directive = line.text[0] == '.' ? directive_of(line.text) : "";
        std::vector<std::string> words = words_of(line.text);
        if (directive == "lib" && words.size() == 2) {  // a section marker: .lib name
          in_wanted_section = parser::lower(words[1]) == section->name;
          section->found |= in_wanted_section;
          continue;
        }
        if (directive == "endl") {
          in_wanted_section = false;
          continue;
        }
        if (!in_wanted_section) continue;
      }
      Parsed parsed = parse_card(line);
      auto& body = open.empty() ? cards : std::get<ast::Subcircuit>(open.back().node).body;
      if (parsed.ends) {
        if (open.empty()) {
          diagnostics_.error(parsed.where, ".ends without .subckt");
          continue;
        }
        ast::Card closed = std::move(open.back());
        open.pop_back();
        const ast::Word& name = std::get<ast::Subcircuit>(closed.node).name;
        if (name.text.empty()) continue;
        if (parsed.ends_name && parsed.ends_name->text != name.text)
          diagnostics_.error(parsed.ends_name->where, "'.ends " + parsed.ends_name->text +
                                                          "' closes subcircuit '" + name.text + "'");
        (open.empty() ? cards : std::get<ast::Subcircuit>(open.back().node).body)
            .push_back(std::move(closed));
      } else if (parsed.opens_subcircuit) {
        // A .subckt line that did not parse still opens a body (an unnamed one, dropped at its
        // .ends), so that the body and the .ends give no follow-up errors.
        open.push_back(parsed.card ? std::move(*parsed.card) : ast::Card{ast::Subcircuit{}, parsed.where});
      } else if (parsed.card) {
        body.push_back(std::move(*parsed.card));
      }
    }
    for (const ast::Card& unclosed : open) {
      const ast::Word& name = std::get<ast::Subcircuit>(unclosed.node).name;
      if (!name.text.empty())
        diagnostics_.error(name.where, "missing .ends for subcircuit '" + name.text + "'");
    }
    return cards;
  }

  template <typename Node, typename Rule>
  Parsed parse_as(const Rule& rule, const LogicalLine& line, SourceRange where) {
    Node node;
    Parsed parsed;
    parsed.where = where;
    if (parse_card_with(rule, node, line, diagnostics_)) parsed.card = ast::Card{std::move(node), where};
    return parsed;
  }

  Parsed parse_card(const LogicalLine& line) {
    const std::string& text = line.text;
    std::size_t first_word_end = text.find_first_of(" \t");
    if (first_word_end == std::string::npos) first_word_end = text.size();
    SourceRange where = line.range(0, first_word_end);
    if (text[0] == '.') return parse_dot_card(line, where);
    switch (std::tolower(static_cast<unsigned char>(text[0]))) {
      case 'r':
      case 'c':
      case 'l':
        return parse_as<ast::TwoTerminal>(parser::two_terminal_card, line, where);
      case 'k':
        return parse_as<ast::Coupling>(parser::coupling_card, line, where);
      case 'v':
      case 'i': {
        Parsed parsed = parse_as<ast::IndependentSource>(parser::source_card, line, where);
        if (parsed.card && !check_source(std::get<ast::IndependentSource>(parsed.card->node)))
          parsed.card.reset();
        return parsed;
      }
      case 'e':
      case 'g':
        if (is_polynomial_card(text)) return parse_as<ast::Polynomial>(parser::polynomial_card, line, where);
        if (is_expression_card(text)) {
          Parsed parsed = parse_as<ast::Behavioral>(parser::expression_controlled_card, line, where);
          if (parsed.card && !as_behavioral(std::get<ast::Behavioral>(parsed.card->node))) parsed.card.reset();
          return parsed;
        }
        return parse_as<ast::VoltageControlled>(parser::voltage_controlled_card, line, where);
      case 'f':
      case 'h':
        if (is_polynomial_card(text)) return parse_as<ast::Polynomial>(parser::polynomial_card, line, where);
        return parse_as<ast::CurrentControlled>(parser::current_controlled_card, line, where);
      case 'b':
        return parse_as<ast::Behavioral>(parser::behavioral_card, line, where);
      case 'd':
        return parse_as<ast::Diode>(parser::diode_card, line, where);
      case 'm':
        return parse_as<ast::Mosfet>(parser::mosfet_card, line, where);
      case 's':
        return parse_as<ast::VoltageSwitch>(parser::voltage_switch_card, line, where);
      case 'w':
        return parse_as<ast::CurrentSwitch>(parser::current_switch_card, line, where);
      case 'x': {
        Parsed parsed = parse_as<ast::Instance>(parser::instance_card, line, where);
        if (parsed.card) {
          auto& instance = std::get<ast::Instance>(parsed.card->node);
          instance.subcircuit = std::move(instance.nodes.back());
          instance.nodes.pop_back();
        }
        return parsed;
      }
      default:
        break;
    }
    Parsed parsed;
    if (std::isalpha(static_cast<unsigned char>(text[0])))
      diagnostics_.error({where.begin, 1}, std::string("unknown element letter '") + text[0] + "'");
    else
      diagnostics_.error({where.begin, 1}, "expected an element or a dot card");
    return parsed;
  }

  // Waveform arity, one waveform and one DC value per source, r= and td= only for pwl.
  // An E card's vol= or value= is a B source's v=, a G card's cur= or value= its i=.
  bool as_behavioral(ast::Behavioral& card) {
    const bool voltage = card.name.text[0] == 'e';
    const std::string& quantity = card.quantity.text;
    if (quantity == (voltage ? "cur" : "vol")) {
      diagnostics_.error(card.quantity.where, std::string(voltage ? "an E source takes vol= or value=, not cur="
                                                                  : "a G source takes cur= or value=, not vol="));
      return false;
    }
    card.quantity.text = voltage ? "v" : "i";
    return true;
  }

  bool check_source(const ast::IndependentSource& source) {
    bool valid = true;
    const ast::SourceSpec* waveform = nullptr;
    const ast::SourceSpec* dc = nullptr;
    for (const ast::SourceSpec& spec : source.specs) {
      const std::string& kind = spec.kind.text;
      if (kind == "ac") continue;
      if (kind.empty() || kind == "dc") {
        if (dc) {
          diagnostics_.error(spec.kind.where, "a second DC value for " + source.name.text);
          valid = false;
        }
        dc = &spec;
        continue;
      }
      if (waveform) {
        diagnostics_.error(spec.kind.where, "a second waveform for " + source.name.text);
        valid = false;
      }
      waveform = &spec;
      for (const WaveformShape& shape : waveform_shapes) {
        if (kind != shape.name) continue;
        std::size_t count = spec.args.size();
        if (count < shape.min_args || count > shape.max_args) {
          std::string expected = shape.max_args > 100
                                     ? "at least " + std::to_string(shape.min_args)
                                     : std::to_string(shape.min_args) + " to " +
                                           std::to_string(shape.max_args);
          diagnostics_.error(spec.kind.where, kind + " takes " + expected + " values, not " +
                                                  std::to_string(count));
          valid = false;
        } else if (kind == "pwl" && count % 2 != 0) {
          diagnostics_.error(spec.kind.where, "pwl takes time-value pairs, not " +
                                                  std::to_string(count) + " values");
          valid = false;
        }
      }
      for (const ast::Assignment& option : spec.options) {
        if (kind != "pwl" || (option.name.text != "r" && option.name.text != "td")) {
          diagnostics_.error(option.name.where,
                             "unknown " + kind + " parameter '" + option.name.text + "'");
          valid = false;
        }
      }
    }
    // As ngspice ("v1: has no value, DC 0 assumed"), which counts an AC magnitude as no value.
    if (!dc && !waveform) diagnostics_.warning(source.name.where, source.name.text + " has no value, DC 0 assumed");
    return valid;
  }

  Parsed parse_dot_card(const LogicalLine& line, SourceRange where) {
    std::string directive = directive_of(line.text);
    if (directive == "param") {
      Parsed parsed;
      parsed.where = where;
      std::vector<ast::Assignment> assignments;
      if (parse_card_with(parser::param_card, assignments, line, diagnostics_))
        parsed.card = ast::Card{ast::ParamCard{std::move(assignments)}, where};
      return parsed;
    }
    if (directive == "model") return parse_as<ast::ModelCard>(parser::model_card, line, where);
    if (directive == "subckt") {
      Parsed parsed = parse_as<ast::Subcircuit>(parser::subckt_card, line, where);
      parsed.opens_subcircuit = true;
      return parsed;
    }
    if (directive == "ends") {
      Parsed parsed;
      parsed.where = where;
      std::optional<ast::Word> name;
      parsed.ends = true;
      if (parse_card_with(parser::ends_card, name, line, diagnostics_)) parsed.ends_name = name;
      return parsed;
    }
    if (directive == "include" || directive == "inc" || directive == "lib")
      return parse_include(line, where);
    if (directive == "endl") {
      diagnostics_.error(where, ".endl outside a library section");
      return {};
    }
    if (directive == "tran") return parse_as<ast::TranCard>(parser::tran_card, line, where);
    if (directive == "ic" || directive == "nodeset")
      return parse_as<ast::NodeValuesCard>(parser::node_values_card, line, where);
    if (directive == "options" || directive == "option" || directive == "opt" || directive == "opts")
      return parse_as<ast::OptionsCard>(parser::options_card, line, where);
    if (directive == "save" || directive == "print" || directive == "probe")
      return parse_as<ast::OutputCard>(parser::output_card, line, where);
    if (directive == "temp") return parse_as<ast::TempCard>(parser::temp_card, line, where);
    if (directive == "global") return parse_as<ast::GlobalCard>(parser::global_card, line, where);
    Parsed parsed;
    parsed.where = where;
    if (directive == "title") {
      std::size_t start = line.text.find_first_not_of(" \t", where.length);
      std::string text = start == std::string::npos ? "" : line.text.substr(start);
      SourceRange text_where = start == std::string::npos ? where : line.range(start, line.text.size());
      parsed.card = ast::Card{ast::TitleCard{std::move(text), text_where}, where};
      return parsed;
    }
    if (is_unsupported_directive(directive)) {
      diagnostics_.error(where, "." + directive + " is not supported by padsim");
      return parsed;
    }
    // Analyses, output-only and unknown cards: elaboration decides whether ignoring them is
    // harmless (it depends on whether there is a .tran).
    parsed.card = ast::Card{ast::IgnoredCard{ast::Word{directive, where}, line.text}, where};
    return parsed;
  }

  Parsed parse_include(const LogicalLine& line, SourceRange where) {
    Parsed parsed = parse_as<ast::Include>(parser::include_card, line, where);
    if (!parsed.card) return parsed;
    auto& include = std::get<ast::Include>(parsed.card->node);
    if (include.directive.text != "lib") include.directive.text = "include";
    if (include.directive.text == "include" && include.section) {
      diagnostics_.error(include.section->where, "unexpected " + quote(include.section->text));
      parsed.card.reset();
      return parsed;
    }
    if (include.directive.text == "lib" && !include.section) {
      SourceRange end = line.range(line.text.size(), line.text.size());
      diagnostics_.error(end, "expected a library section name");
      parsed.card.reset();
      return parsed;
    }
    namespace fs = std::filesystem;
    fs::path path = include.path.text;
    if (path.is_relative()) path = fs::path(line.file->path).parent_path() / path;
    std::error_code error;
    fs::path canonical = fs::weakly_canonical(path, error);
    if (error) canonical = path;
    for (std::size_t i = 0; i < include_stack_.size(); ++i) {
      std::error_code ignored;
      if (fs::weakly_canonical(include_stack_[i], ignored) != canonical) continue;
      std::string cycle;
      for (std::size_t j = i; j < include_stack_.size(); ++j) cycle += include_stack_[j] + " -> ";
      diagnostics_.error(include.path.where, "include cycle: " + cycle + path.string());
      parsed.card.reset();
      return parsed;
    }
    std::string why;
    auto file = read_source(path, why);
    if (!file) {
      diagnostics_.error(include.path.where, "cannot read '" + path.string() + "': " + why);
      parsed.card.reset();
      return parsed;
    }
    SplitFile split = split_lines(file, false, diagnostics_);
    include_stack_.push_back(file->path);
    if (include.section) {
      Section section{include.section->text};
      include.cards = parse_cards(split, &section);
      if (!section.found)
        diagnostics_.error(include.section->where, "library section '" + section.name +
                                                       "' not found in '" + path.string() + "'");
    } else {
      include.cards = parse_cards(split, nullptr);
    }
    include_stack_.pop_back();
    return parsed;
  }

  Diagnostics& diagnostics_;
  std::vector<std::string> include_stack_;  // files being read, outermost first
};

}  // namespace

ast::Netlist parse_text(std::string text, std::string path, Diagnostics& diagnostics) {
  auto file = std::make_shared<const SourceFile>(std::move(path), std::move(text));
  return Parser(diagnostics).parse_top(file);
}

ast::Netlist parse_file(const std::filesystem::path& path, Diagnostics& diagnostics) {
  std::string why;
  auto file = read_source(path, why);
  if (!file) {
    diagnostics.error({}, "cannot read '" + path.string() + "': " + why);
    return {};
  }
  return Parser(diagnostics).parse_top(file);
}

std::optional<double> parse_number(std::string_view text) {
  std::string copy(text);
  return parser::number_value(copy.cbegin(), copy.cend());
}

}  // namespace netlist

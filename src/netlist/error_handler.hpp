// What the grammar's semantic actions and its error handler need about the card being parsed:
// the map from the card's text back to the file, and where diagnostics go. Injected into the
// parse with x3::with<card_context_tag>.
#pragma once

#include <string>

#include <boost/spirit/home/x3.hpp>

#include "netlist/lines.hpp"
#include "netlist/source.hpp"

namespace netlist::parser {

namespace x3 = boost::spirit::x3;
using Iterator = std::string::const_iterator;

struct card_context_tag;

// A semantic error found while parsing (unknown function, wrong arity, bad number), thrown
// out of the X3 parse and reported by the card parser.
struct CardError {
  SourceRange where;
  std::string message;
};

class CardContext {
 public:
  CardContext(const LogicalLine& line, Diagnostics& diagnostics)
      : line_(line), diagnostics_(diagnostics) {}

  SourceRange range(Iterator first, Iterator last) const {
    return line_.range(offset(first), offset(last));
  }

  // The token at `where` (up to the next blank), for carets and "unexpected" messages.
  SourceRange token_range(Iterator where) const;
  std::string token(Iterator where) const;

  // Reports an expectation failure: "expected <what>", or "unexpected '<token>'" when the card
  // should have ended.
  void expected(Iterator where, const std::string& what) const;

  Iterator begin() const { return line_.text.begin(); }

  // Nesting depth of the expression being parsed: bounded so that the recursive descent
  // cannot exhaust the stack ("((((..." or "- - - -...").
  int nesting = 0;
  Iterator end() const { return line_.text.end(); }

 private:
  std::size_t offset(Iterator it) const {
    return static_cast<std::size_t>(it - line_.text.begin());
  }
  const LogicalLine& line_;
  Diagnostics& diagnostics_;
};

// Base of the card rules' IDs: an expectation failure anywhere inside a card ends up here.
struct card_error_handler {
  template <typename It, typename Exception, typename Context>
  x3::error_handler_result on_error(It&, It const&, Exception const& failure,
                                    Context const& context) {
    x3::get<card_context_tag>(context).get().expected(failure.where(), failure.which());
    return x3::error_handler_result::fail;
  }
};

}  // namespace netlist::parser

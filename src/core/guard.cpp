// Recursive-descent parser for guard expressions into a flat node array, and an allocation-free
// evaluator over it. Grammar (lowest precedence first):
//   or   := and ('||' and)*
//   and  := not ('&&' not)*
//   not  := '!' not | cmp
//   cmp  := primary (('=='|'!='|'<'|'<='|'>'|'>=') primary)?
//   primary := NUMBER | STRING | 'true' | 'false' | IDENT | '(' or ')'
// IDENT is [A-Za-z_][A-Za-z0-9_.]* ; STRING is '...' or "..." without escapes.
#include "tripodal/core/guard.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>

namespace tripodal {

GuardSyntaxError::GuardSyntaxError(int column, const std::string& message)
    : std::runtime_error("column " + std::to_string(column) + ": " + message), column_(column) {}

namespace {

enum class Op : std::uint8_t { literal, ident, logical_not, logical_and, logical_or, eq, ne, lt, le, gt, ge };

struct Node {
  Op op = Op::literal;
  std::uint32_t a = 0;  // first child, or slot for ident, or literal index
  std::uint32_t b = 0;  // second child
};

// The result of evaluating a node: a view, never an owning copy, so evaluation does not allocate.
struct Operand {
  ValueType type = ValueType::boolean;
  bool boolean = false;
  double number = 0.0;
  const std::string* string = nullptr;
  bool valid = true;  // false: an identifier with no value
};

}  // namespace

struct Guard::Impl {
  std::string text;
  std::vector<std::string> identifiers;
  std::vector<std::optional<ValueType>> expected;
  std::vector<Value> literals;
  std::vector<Node> nodes;
  std::uint32_t root = 0;

  Operand eval(std::uint32_t n, std::span<const Value* const> slots) const noexcept;
  Guard::Truth partial(std::uint32_t n, std::span<const Value* const> slots) const noexcept;
  bool reads_unknown(std::uint32_t n, std::span<const Value* const> slots) const noexcept;
  bool truth(std::uint32_t n, std::span<const Value* const> slots) const noexcept {
    const Operand o = eval(n, slots);
    return o.valid && o.type == ValueType::boolean && o.boolean;
  }
};

namespace {

class Parser {
 public:
  Parser(std::string_view text, Guard::Impl& out) : s_(text), out_(out) {}

  std::uint32_t parse() {
    skip_space();
    if (pos_ == s_.size()) fail(pos_, "empty guard: expected an expression");
    const std::uint32_t root = parse_or();
    skip_space();
    if (pos_ != s_.size()) fail(pos_, "unexpected '" + std::string(1, s_[pos_]) + "' after a complete expression");
    mark_condition(root);
    return root;
  }

 private:
  [[noreturn]] void fail(std::size_t at, const std::string& message) const {
    throw GuardSyntaxError(static_cast<int>(at) + 1, message);
  }

  void skip_space() {
    // isspace() of the "C" locale, without the call.
    const auto space = [](char c) { return c == ' ' || (c >= '\t' && c <= '\r'); };
    while (pos_ < s_.size() && space(s_[pos_])) ++pos_;
  }

  bool accept(std::string_view token) {
    skip_space();
    if (s_.substr(pos_, token.size()) == token) {
      pos_ += token.size();
      return true;
    }
    return false;
  }

  std::uint32_t add(Op op, std::uint32_t a = 0, std::uint32_t b = 0) {
    out_.nodes.push_back({op, a, b});
    return static_cast<std::uint32_t>(out_.nodes.size() - 1);
  }

  // Operands of !, && and || are conditions: an identifier there must be a boolean.
  void mark_condition(std::uint32_t n) {
    const Node& node = out_.nodes[n];
    if (node.op == Op::ident && !out_.expected[node.a]) out_.expected[node.a] = ValueType::boolean;
  }

  std::uint32_t parse_or() {
    std::uint32_t left = parse_and();
    while (accept("||")) {
      const std::uint32_t right = parse_and();
      mark_condition(left);
      mark_condition(right);
      left = add(Op::logical_or, left, right);
    }
    return left;
  }

  std::uint32_t parse_and() {
    std::uint32_t left = parse_not();
    while (accept("&&")) {
      const std::uint32_t right = parse_not();
      mark_condition(left);
      mark_condition(right);
      left = add(Op::logical_and, left, right);
    }
    return left;
  }

  std::uint32_t parse_not() {
    skip_space();
    if (pos_ < s_.size() && s_[pos_] == '!' && s_.substr(pos_, 2) != "!=") {
      ++pos_;
      const std::uint32_t operand = parse_not();
      mark_condition(operand);
      return add(Op::logical_not, operand);
    }
    return parse_cmp();
  }

  std::uint32_t parse_cmp() {
    const std::uint32_t left = parse_primary();
    skip_space();
    static constexpr std::pair<std::string_view, Op> kOps[] = {
        {"==", Op::eq}, {"!=", Op::ne}, {"<=", Op::le}, {">=", Op::ge}, {"<", Op::lt}, {">", Op::gt}};
    for (const auto& [token, op] : kOps) {
      if (s_.substr(pos_, token.size()) == token) {
        pos_ += token.size();
        const std::uint32_t right = parse_primary();
        infer(left, right, op);
        infer(right, left, op);
        return add(op, left, right);
      }
    }
    if (pos_ < s_.size() && s_[pos_] == '=') fail(pos_, "'=' is not an operator; use '==' to compare");
    return left;
  }

  // An identifier compared with a literal is expected to have the literal's type.
  void infer(std::uint32_t ident, std::uint32_t other, Op op) {
    const Node& a = out_.nodes[ident];
    const Node& b = out_.nodes[other];
    if (a.op != Op::ident) return;
    if (b.op == Op::literal) {
      if (!out_.expected[a.a]) out_.expected[a.a] = type_of(out_.literals[b.a]);
    } else if (op != Op::eq && op != Op::ne && !out_.expected[a.a]) {
      out_.expected[a.a] = ValueType::number;
    }
  }

  std::uint32_t literal(Value v) {
    out_.literals.push_back(std::move(v));
    return add(Op::literal, static_cast<std::uint32_t>(out_.literals.size() - 1));
  }

  std::uint32_t parse_primary() {
    skip_space();
    if (pos_ >= s_.size()) fail(pos_, "unexpected end of guard: expected a value, a name or '('");
    const char c = s_[pos_];
    const std::size_t start = pos_;
    if (c == '(') {
      ++pos_;
      const std::uint32_t inner = parse_or();
      skip_space();
      if (pos_ >= s_.size() || s_[pos_] != ')') fail(pos_, "expected ')' to close the '(' at column " + std::to_string(start + 1));
      ++pos_;
      return inner;
    }
    if (c == '\'' || c == '"') {
      const std::size_t end = s_.find(c, pos_ + 1);
      if (end == std::string_view::npos) fail(start, "unterminated string");
      pos_ = end + 1;
      return literal(Value{std::string(s_.substr(start + 1, end - start - 1))});
    }
    if (std::isdigit(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '.') {
      std::size_t end = pos_ + 1;
      while (end < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[end])) != 0 || s_[end] == '.' ||
                                 ((s_[end] == '-' || s_[end] == '+') && (s_[end - 1] == 'e' || s_[end - 1] == 'E')))) {
        ++end;
      }
      double x = 0.0;
      const char* first = s_.data() + pos_;
      const char* last = s_.data() + end;
      const auto [ptr, ec] = std::from_chars(first, last, x);
      if (ec != std::errc{} || ptr != last || !std::isfinite(x)) {
        fail(start, "bad number '" + std::string(s_.substr(start, end - start)) + "'");
      }
      pos_ = end;
      return literal(Value{x});
    }
    if (std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_') {
      std::size_t end = pos_ + 1;
      while (end < s_.size() &&
             (std::isalnum(static_cast<unsigned char>(s_[end])) != 0 || s_[end] == '_' || s_[end] == '.')) {
        ++end;
      }
      const std::string_view word = s_.substr(pos_, end - pos_);
      pos_ = end;
      if (word == "true") return literal(Value{true});
      if (word == "false") return literal(Value{false});
      for (std::size_t i = 0; i < out_.identifiers.size(); ++i) {
        if (out_.identifiers[i] == word) return add(Op::ident, static_cast<std::uint32_t>(i));
      }
      out_.identifiers.emplace_back(word);
      out_.expected.emplace_back();
      return add(Op::ident, static_cast<std::uint32_t>(out_.identifiers.size() - 1));
    }
    fail(start, "unexpected '" + std::string(1, c) + "': expected a value, a name or '('");
  }

  std::string_view s_;
  std::size_t pos_ = 0;
  Guard::Impl& out_;
};

Operand operand_of(const Value& v) noexcept {
  Operand o;
  o.type = type_of(v);
  switch (o.type) {
    // get_if, not get: the type is known, and get's bad_variant_access could not leave noexcept.
    case ValueType::boolean: o.boolean = *std::get_if<bool>(&v); break;
    case ValueType::number: o.number = *std::get_if<double>(&v); break;
    case ValueType::string: o.string = std::get_if<std::string>(&v); break;
  }
  return o;
}

template <typename T>
bool compare(Op op, const T& a, const T& b) noexcept {
  switch (op) {
    case Op::eq: return a == b;
    case Op::ne: return a != b;
    case Op::lt: return a < b;
    case Op::le: return a <= b;
    case Op::gt: return a > b;
    case Op::ge: return a >= b;
    default: return false;
  }
}

Operand boolean(bool b) noexcept {
  Operand o;
  o.boolean = b;
  return o;
}

}  // namespace

Operand Guard::Impl::eval(std::uint32_t n, std::span<const Value* const> slots) const noexcept {
  const Node& node = nodes[n];
  switch (node.op) {
    case Op::literal: return operand_of(literals[node.a]);
    case Op::ident: {
      if (node.a >= slots.size() || slots[node.a] == nullptr) {
        Operand missing;
        missing.valid = false;
        return missing;
      }
      return operand_of(*slots[node.a]);
    }
    case Op::logical_not: return boolean(!truth(node.a, slots));
    case Op::logical_and: return boolean(truth(node.a, slots) && truth(node.b, slots));
    case Op::logical_or: return boolean(truth(node.a, slots) || truth(node.b, slots));
    default: break;
  }
  const Operand a = eval(node.a, slots);
  const Operand b = eval(node.b, slots);
  // Comparisons with a missing value or across types are false (and so is their negation '!=').
  if (!a.valid || !b.valid || a.type != b.type) return boolean(false);
  switch (a.type) {
    case ValueType::boolean: return boolean(compare(node.op, a.boolean, b.boolean));
    case ValueType::number: return boolean(compare(node.op, a.number, b.number));
    case ValueType::string: return boolean(compare(node.op, *a.string, *b.string));
  }
  return boolean(false);
}

bool Guard::Impl::reads_unknown(std::uint32_t n, std::span<const Value* const> slots) const noexcept {
  const Node& node = nodes[n];
  switch (node.op) {
    case Op::literal:
      return false;
    case Op::ident:
      return node.a >= slots.size() || slots[node.a] == nullptr;
    case Op::logical_not:
      return reads_unknown(node.a, slots);
    default:
      return reads_unknown(node.a, slots) || reads_unknown(node.b, slots);
  }
}

// Kleene's logic over the same rules as truth(): a node that reads no unknown value is decided
// by eval(); otherwise the connectives decide what they can without it.
Guard::Truth Guard::Impl::partial(std::uint32_t n, std::span<const Value* const> slots) const noexcept {
  const Node& node = nodes[n];
  if (!reads_unknown(n, slots)) return truth(n, slots) ? Truth::yes : Truth::no;
  switch (node.op) {
    case Op::logical_not: {
      const Truth a = partial(node.a, slots);
      return a == Truth::unknown ? a : (a == Truth::yes ? Truth::no : Truth::yes);
    }
    case Op::logical_and: {
      const Truth a = partial(node.a, slots);
      const Truth b = partial(node.b, slots);
      if (a == Truth::no || b == Truth::no) return Truth::no;
      return a == Truth::yes && b == Truth::yes ? Truth::yes : Truth::unknown;
    }
    case Op::logical_or: {
      const Truth a = partial(node.a, slots);
      const Truth b = partial(node.b, slots);
      if (a == Truth::yes || b == Truth::yes) return Truth::yes;
      return a == Truth::no && b == Truth::no ? Truth::no : Truth::unknown;
    }
    default:
      return Truth::unknown;  // an unknown identifier, or a comparison reading one
  }
}

Guard Guard::parse(std::string_view text) {
  auto impl = std::make_unique<Impl>();
  impl->text = std::string(text);
  // Room for a typical guard ("mode == 'fast' || mode == 'safe'" has 7 nodes): a load of
  // thousands of guards otherwise spends its time growing these one entry at a time.
  impl->nodes.reserve(8);
  impl->literals.reserve(4);
  impl->identifiers.reserve(2);
  impl->expected.reserve(2);
  Parser parser(text, *impl);
  impl->root = parser.parse();
  return Guard(std::move(impl));
}

Guard::Guard(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Guard::Guard(const Guard& other) : impl_(std::make_unique<Impl>(*other.impl_)) {}
Guard& Guard::operator=(const Guard& other) {
  if (this != &other) impl_ = std::make_unique<Impl>(*other.impl_);
  return *this;
}
Guard::Guard(Guard&&) noexcept = default;
Guard& Guard::operator=(Guard&&) noexcept = default;
Guard::~Guard() = default;

const std::string& Guard::text() const noexcept { return impl_->text; }
const std::vector<std::string>& Guard::identifiers() const noexcept { return impl_->identifiers; }
std::optional<ValueType> Guard::expected_type(std::size_t slot) const noexcept {
  return slot < impl_->expected.size() ? impl_->expected[slot] : std::nullopt;
}
std::vector<Value> Guard::compared_literals(std::size_t slot) const {
  std::vector<Value> out;
  for (const Node& n : impl_->nodes) {
    if (n.op < Op::eq) continue;  // only the comparisons
    const Node& a = impl_->nodes[n.a];
    const Node& b = impl_->nodes[n.b];
    const Node* literal = nullptr;
    if (a.op == Op::ident && a.a == slot && b.op == Op::literal) literal = &b;
    if (b.op == Op::ident && b.a == slot && a.op == Op::literal) literal = &a;
    if (literal == nullptr) continue;
    const Value& v = impl_->literals[literal->a];
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  }
  return out;
}

bool Guard::evaluate(std::span<const Value* const> slots) const noexcept { return impl_->truth(impl_->root, slots); }

Guard::Truth Guard::partial_evaluate(std::span<const Value* const> slots) const noexcept {
  return impl_->partial(impl_->root, slots);
}

}  // namespace tripodal

// Two error tiers (docs/architecture.md):
//  * InputError: bad user input (files, JSON, images, flags). Thrown, never aborts; the message names
//    the file, the place inside it (a JSON pointer, a view name) and what was expected.
//  * WGS_CHECK*: internal invariants (programmer mistakes). Throws InternalError with both operands,
//    so a host process can still report it; the CLI maps it to exit code 3.
//  * NumericalDivergence: valid input on which a numerical process stopped being finite (exit 4).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace weathergs {

class InputError : public std::runtime_error {
 public:
  // `where`: a file path, optionally with a location ("cameras.json:/views/3/fx"); may be empty.
  InputError(const std::string& where, const std::string& what)
      : std::runtime_error(where.empty() ? what : where + ": " + what), where_(where), what_(what) {}
  const std::string& where() const { return where_; }
  const std::string& problem() const { return what_; }

 private:
  std::string where_, what_;
};

class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// A numerical process stopped being finite on valid input (e.g. a diverged training): neither bad
// input nor a broken invariant, so the CLI gives it its own exit code (4, docs/architecture.md).
class NumericalDivergence : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
template <typename A, typename B>
[[noreturn]] void check_failed(const char* file, int line, const char* expr, const A& a, const B& b) {
  std::ostringstream s;
  s << "internal check failed at " << file << ":" << line << ": " << expr << " (" << a << " vs " << b
    << ")";
  throw InternalError(s.str());
}
[[noreturn]] inline void check_failed(const char* file, int line, const char* expr) {
  std::ostringstream s;
  s << "internal check failed at " << file << ":" << line << ": " << expr;
  throw InternalError(s.str());
}
}  // namespace detail

}  // namespace weathergs

#define WGS_CHECK(cond) \
  ((cond) ? (void)0 : ::weathergs::detail::check_failed(__FILE__, __LINE__, #cond))
#define WGS_CHECK_OP(a, op, b)                                                                \
  do {                                                                                        \
    const auto& wgs_a_ = (a);                                                                 \
    const auto& wgs_b_ = (b);                                                                 \
    if (!(wgs_a_ op wgs_b_))                                                                  \
      ::weathergs::detail::check_failed(__FILE__, __LINE__, #a " " #op " " #b, wgs_a_, wgs_b_); \
  } while (0)
#define WGS_CHECK_EQ(a, b) WGS_CHECK_OP(a, ==, b)
#define WGS_CHECK_NE(a, b) WGS_CHECK_OP(a, !=, b)
#define WGS_CHECK_LT(a, b) WGS_CHECK_OP(a, <, b)
#define WGS_CHECK_LE(a, b) WGS_CHECK_OP(a, <=, b)
#define WGS_CHECK_GT(a, b) WGS_CHECK_OP(a, >, b)
#define WGS_CHECK_GE(a, b) WGS_CHECK_OP(a, >=, b)

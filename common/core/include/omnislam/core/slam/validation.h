// Small helpers for the validate() methods of the SLAM options structs: each check names the
// field and its accepted range, and the first failing check becomes the returned message.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace omnislam::slam::detail {

/// Accumulates the first failure; `ok()` stays true while every check passes.
class FieldChecker {
 public:
  explicit FieldChecker(std::string prefix = {}) : prefix_(std::move(prefix)) {}

  /// lo <= value <= hi (bounds may be +-infinity); value must not be NaN.
  FieldChecker& inClosed(const char* field, double value, double lo, double hi) {
    if (!message_.empty()) return *this;
    if (!(value >= lo && value <= hi)) fail(field, value, "[", lo, hi, "]");
    return *this;
  }
  /// lo < value <= hi.
  FieldChecker& inLeftOpen(const char* field, double value, double lo, double hi) {
    if (!message_.empty()) return *this;
    if (!(value > lo && value <= hi)) fail(field, value, "(", lo, hi, "]");
    return *this;
  }
  /// lo < value < hi.
  FieldChecker& inOpen(const char* field, double value, double lo, double hi) {
    if (!message_.empty()) return *this;
    if (!(value > lo && value < hi)) fail(field, value, "(", lo, hi, ")");
    return *this;
  }
  /// lo <= value < hi.
  FieldChecker& inRightOpen(const char* field, double value, double lo, double hi) {
    if (!message_.empty()) return *this;
    if (!(value >= lo && value < hi)) fail(field, value, "[", lo, hi, ")");
    return *this;
  }
  /// A free-form condition on one field.
  FieldChecker& require(bool condition, const char* field, const std::string& what) {
    if (message_.empty() && !condition) message_ = prefix_ + field + " " + what;
    return *this;
  }
  /// Adopts the message of a nested options struct's validate(), prefixed with its field name.
  FieldChecker& nested(const char* field, const std::string& nested_message) {
    if (message_.empty() && !nested_message.empty()) message_ = prefix_ + field + "." + nested_message;
    return *this;
  }
  const std::string& message() const { return message_; }

 private:
  void fail(const char* field, double value, const char* open, double lo, double hi, const char* close) {
    char buf[160];
    std::snprintf(buf, sizeof buf, " must be in %s%g, %g%s, got %g", open, lo, hi, close, value);
    message_ = prefix_ + field + buf;
  }
  std::string prefix_;
  std::string message_;
};

}  // namespace omnislam::slam::detail

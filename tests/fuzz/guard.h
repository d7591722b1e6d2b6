// The oracle every fuzz entry point shares: the exceptions a reader documents (Allowed...) are its
// way of refusing bytes; any other exception is a finding (reportUnexpected aborts, so libFuzzer
// saves the input and the regression test fails on it).
#pragma once

#include <exception>
#include <string>
#include <typeinfo>

#include "entry_points.h"

namespace omnislam::fuzz {

/// Whether the exception in `p` is a T.
template <class T>
bool isA(const std::exception_ptr& p) {
  try {
    std::rethrow_exception(p);
  } catch (const T&) {
    return true;
  } catch (...) {
    return false;
  }
}

/// Runs fn; returns normally when it ends or throws one of Allowed..., else reports the exception.
template <class... Allowed, class Fn>
void guard(const char* target, Fn&& fn) {
  try {
    fn();
  } catch (...) {
    const std::exception_ptr p = std::current_exception();
    if ((false || ... || isA<Allowed>(p))) return;
    try {
      std::rethrow_exception(p);
    } catch (const std::exception& e) {
      reportUnexpected(target, typeid(e).name(), e.what());
    } catch (...) {
      reportUnexpected(target, "a non-standard exception", "");
    }
  }
}

}  // namespace omnislam::fuzz

#pragma once
// expect_input_error(f, words): f() must throw cgd::InputError whose message holds every one of `words`
// (the file, the key, the value, what is allowed: the parts a bad-input message must name).
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace cgd::testing {

inline void expect_input_error(const std::function<void()>& f, const std::vector<std::string>& words) {
  try {
    f();
    ADD_FAILURE() << "no InputError";
  } catch (const cgd::InputError& e) {
    for (const auto& w : words)
      EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << e.what() << " lacks " << w;
  }
}

}  // namespace cgd::testing

#pragma once
// Helpers shared by the diagnose tests (test_diagnose*.cpp).
#include "ov_eval/diagnose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace ovtest {

inline const ovton::eval::CandidateResult &top(const ovton::eval::DiagnoseReport &r) {
  return r.candidates.front();
}

inline double estimate(const ovton::eval::CandidateResult &c, const std::string &name) {
  for (const auto &e : c.estimates)
    if (e.name == name)
      return e.value;
  ADD_FAILURE() << c.key << " has no estimate '" << name << "'";
  return std::nan("");
}

/// The planted effect is ranked first, explained, and its estimate `name` lies within tol of `value`.
inline void expect_top(const ovton::eval::DiagnoseReport &r, const std::string &key, const std::string &name,
                       double value, double tol) {
  ASSERT_FALSE(r.candidates.empty());
  EXPECT_TRUE(top(r).explained) << ovton::eval::format_ranking(r);
  EXPECT_EQ(top(r).key, key) << ovton::eval::format_ranking(r);
  if (top(r).key == key) { // braces: EXPECT_* expands to an if/else
    EXPECT_NEAR(estimate(top(r), name), value, tol) << ovton::eval::format_ranking(r);
  }
}

/// No candidate selected and no structure left that none explains (the UNEXPLAINED verdict).
inline void expect_nothing_flagged(const ovton::eval::DiagnoseReport &r) {
  for (const auto &c : r.candidates)
    EXPECT_FALSE(c.explained) << ovton::eval::format_ranking(r);
  for (const auto &u : r.unexplained)
    EXPECT_FALSE(u.flagged) << ovton::eval::format_ranking(r);
}

} // namespace ovtest

// The calibration operator's spellings (core/schema/calibration.hpp).
#include "core/schema/calibration.hpp"

namespace cgd {

const CalibrationOperatorNames& names_of(CalibrationOperator op) {
  for (const CalibrationOperatorNames& n : kCalibrationOperators)
    if (n.op == op) return n;
  return kCalibrationOperators[0];  // unreachable: every enumerator has its row
}

std::optional<CalibrationOperator> parse_calibration_operator(const std::string& text,
                                                              const char* CalibrationOperatorNames::*place) {
  for (const CalibrationOperatorNames& n : kCalibrationOperators)
    if (text == n.*place) return n.op;
  return std::nullopt;
}

std::string calibration_operator_choices(const char* CalibrationOperatorNames::*place) {
  std::string out;
  for (const CalibrationOperatorNames& n : kCalibrationOperators)
    out += (out.empty() ? "\"" : " or \"") + std::string(n.*place) + "\"";
  return out;
}

}  // namespace cgd

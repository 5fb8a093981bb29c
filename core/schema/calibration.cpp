// The calibration operator's one spelling (core/schema/calibration.hpp).
#include "core/schema/calibration.hpp"

namespace cgd {

namespace {

struct OperatorName {
  CalibrationOperator op;
  const char* text;
};
constexpr OperatorName kOperators[] = {{CalibrationOperator::Box, "box"}, {CalibrationOperator::Grid, "grid"}};

}  // namespace

const char* to_string(CalibrationOperator op) {
  for (const OperatorName& n : kOperators)
    if (n.op == op) return n.text;
  return kOperators[0].text;  // unreachable: every enumerator has its row
}

std::optional<CalibrationOperator> parse_calibration_operator(const std::string& text) {
  for (const OperatorName& n : kOperators)
    if (text == n.text) return n.op;
  return std::nullopt;
}

std::string calibration_operator_choices() {
  std::string out;
  for (const OperatorName& n : kOperators) out += (out.empty() ? "\"" : " or \"") + std::string(n.text) + "\"";
  return out;
}

}  // namespace cgd

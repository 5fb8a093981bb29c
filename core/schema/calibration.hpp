#pragma once
// The calibration operator, one idea with three spellings kept for the files already written and the
// command line (docs/schema-drag-model.md "Calibration", docs/schema-filtered.md "/grids"): the enum the
// code holds, and the one table of its spellings with the conversions. Only this file and the format
// files of core/schema/ spell the operator as text.
#include <optional>
#include <string>

namespace cgd {

/// The filter a filtered law is calibrated on: the particle-centred box of width Delta, or a coarse grid's
/// TSC deposit and interpolation (Delta = its cell size).
enum class CalibrationOperator { Box, TscGrid };

/// One row per operator: how each place spells it.
struct CalibrationOperatorNames {
  CalibrationOperator op;
  const char* option;         // cgd-fit --operator
  const char* model_file;     // drag model file, root attribute `operator`
  const char* filtered_file;  // filtered file: the width groups' `kind`, the grids' `operator`
};
inline constexpr CalibrationOperatorNames kCalibrationOperators[] = {
    {CalibrationOperator::Box, "box", "box", "box"},
    {CalibrationOperator::TscGrid, "grid", "tsc-grid", "tsc-deposit-interpolate"},
};
const CalibrationOperatorNames& names_of(CalibrationOperator op);
/// The operator spelled `text` in `place` (&CalibrationOperatorNames::option, ::model_file, ::filtered_file).
std::optional<CalibrationOperator> parse_calibration_operator(const std::string& text,
                                                              const char* CalibrationOperatorNames::*place);
/// "\"box\" or \"grid\"": the spellings of `place`, for messages.
std::string calibration_operator_choices(const char* CalibrationOperatorNames::*place);

}  // namespace cgd

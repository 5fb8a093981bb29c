#pragma once
// The calibration operator, one idea with one spelling (docs/schema-drag-model.md "Calibration",
// docs/schema-filtered.md "/grids"): "box" or "grid" on cgd-fit's command line (--operator), in the drag
// model file's root attribute `operator` and in the filtered file's width groups' `kind` and grids'
// `operator`. The enum the code holds and its one to_string/parse. Files of format version 1 spelled the
// grid operator otherwise ("tsc-grid" in model files, "tsc-deposit-interpolate" in filtered files): their
// readers map those spellings in one place each (core/schema/drag_model.cpp, core/schema/filtered.cpp:
// upgrade_version1), nowhere else.
#include <optional>
#include <string>

namespace cgd {

/// The filter a filtered law is calibrated on: the particle-centred box of width Delta, or a coarse grid's
/// TSC deposit and interpolation (Delta = its cell size; the kernel is recorded apart, `kernel` = "tsc").
enum class CalibrationOperator { Box, Grid };

/// "box", "grid".
const char* to_string(CalibrationOperator op);
/// The operator spelled `text` ("box" or "grid"); nullopt for anything else.
std::optional<CalibrationOperator> parse_calibration_operator(const std::string& text);
/// "\"box\" or \"grid\"": the spellings, for messages.
std::string calibration_operator_choices();

}  // namespace cgd

"""The spellings the Python tools share with cgd's schema layer (core/schema/), and the one upgrade path of
version-1 files: docs/schema-drag-model.md "Versions" and docs/schema-filtered.md "Versions".

Version 2 of the drag model and filtered files spells each idea once, as core/schema/ does: the microscopic law
under the root attribute `micro_drag`, the calibration operator "box" or "grid". Version 1 (the files written
before, among them the half-box model of tests/data/half_box_v1.h5) stored the model's law under `base_drag` and
spelled the grid operator "tsc-grid" (model files) or "tsc-deposit-interpolate" (the filtered file's grids). A tool reads these
two ideas through micro_law() and calibration_operator(), never by the old names, so that this module and
core/schema/drag_model.cpp / core/schema/filtered.cpp (upgrade_version1) are the only places that know them.
"""

MICRO_LAW = "micro_drag"
BOX, GRID = "box", "grid"
# version 1's spellings, by cgd_format (the only upgrade path; tests/schema/tool_names.py checks no other tool spells them)
VERSION1_MICRO_LAW = {"drag_model": "base_drag"}
VERSION1_GRID_OPERATOR = {"drag_model": "tsc-grid", "filtered": "tsc-deposit-interpolate"}


def _text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def _format(attrs):
    """(cgd_format, cgd_format_version) of a file's root attributes."""
    return _text(attrs.get("cgd_format", "")), int(attrs.get("cgd_format_version", 0))


def micro_law(attrs, default=None):
    """The microscopic drag law of a filtered or drag model file, given its root attributes (default: absent)."""
    kind, version = _format(attrs)
    key = VERSION1_MICRO_LAW.get(kind, MICRO_LAW) if version == 1 else MICRO_LAW
    return _text(attrs[key]) if key in attrs else default


def calibration_operator(attrs, default=BOX):
    """The calibration operator ("box" or "grid") of a drag model file or a filtered file's grid group, given the
    attributes of the object that holds `operator` and the file's root attributes in root (for the version)."""
    return upgraded_operator(attrs.get("operator"), attrs, default)


def upgraded_operator(value, root_attrs, default=BOX):
    """The operator `value` as version 2 spells it, `root_attrs` the file's root attributes (its version)."""
    if value is None:
        return default
    value = _text(value)
    kind, version = _format(root_attrs)
    if version == 1 and value == VERSION1_GRID_OPERATOR.get(kind):
        return GRID
    return value

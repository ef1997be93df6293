/* Unit tests of the model reader on malformed models (tests/models/bad/): every file must fail
 * with CUPID_ERR_MODEL and the exact "FILE:LINE:COL: KEY: message"; random mutations of the
 * valid models must never crash. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

typedef struct {
  const char *file;     /* under tests/models/bad/ */
  const char *expected; /* "LINE:COL: KEY: message" (a prefix of the message after the file) */
  const char *also;     /* another fragment the message must hold, or NULL */
} bad_case;

static const bad_case cases[] = {
    {"alias_expansion_valid_keys.yaml",
     "99:8: model too large or alias expansion too deep (more than 1000000 nodes visited)",
     "alias expansion too deep"},
    {"alias_wrong_type.yaml",
     "2:10: peridynamics.spacing: must be a number, got a mapping",
     NULL},
    {"analysis_type_typo.yaml",
     "8:18: analysis.type: must be one of static | dynamic | evaluate, got 'statc'; did you me",
     "did you mean 'static'?"},
    {"anchors_too_many.yaml",
     "1001:8: more than 1000 anchors (&name)",
     NULL},
    {"area_in_3d.yaml",
     "6:9: peridynamics.area: is only used with dimension: 1",
     NULL},
    {"area_missing_1d.yaml",
     "4:3: peridynamics: missing required key 'area' (dimension 1 needs the bar's",
     NULL},
    {"area_zero.yaml",
     "2:73: peridynamics.area: must be > 0, got 0",
     NULL},
    {"arlequin_missing.yaml",
     "16:3: coupling: missing required key 'arlequin' (method arlequin needs {penalty: ...,",
     NULL},
    {"arlequin_penalty_word.yaml",
     "18:23: coupling.arlequin.penalty: must be a positive number or auto, got 'automatic'",
     NULL},
    {"arlequin_wrong_method.yaml",
     "17:13: coupling.arlequin: is only used with method: arlequin",
     NULL},
    {"axis_not_increasing.yaml",
     "5:21: beam.axis.y[2]: breakpoints must increase, got 30 after 30",
     NULL},
    {"axis_one_point.yaml",
     "5:13: beam.axis.y: must be a list of at least 2 increasing numbers, got 1 item",
     NULL},
    {"bad_te.yaml",
     "7:16: beam.section.expansion: TE needs its order as a whole number N >= 0, e.g. TE2;",
     NULL},
    {"beam_type_bad.yaml",
     "5:58: beam.axis.type: must be one of B2 | B3 | B4, got 'B5'; did you mean 'B2'?",
     NULL},
    {"billion_laughs.yaml",
     "8:45: model too large or alias expansion too deep (more than 1000000 nodes visited)",
     "alias expansion too deep"},
    {"bool_bad.yaml",
     "9:8: output.vtu: must be true or false, got 'yes'",
     NULL},
    {"box_empty.yaml",
     "9:16: constraints[0].fix.box: a box needs at least one of x, y, z, each [min, max]",
     NULL},
    {"box_inverted.yaml",
     "9:20: constraints[0].fix.box.y: must be [min, max] with min <= max, got [5, 1]",
     NULL},
    {"case_key.yaml",
     "5:3: peridynamics.Horizon: unknown key; did you mean 'horizon'?",
     NULL},
    {"comments_only.yaml",
     "1:1: the model file is empty",
     NULL},
    {"component_missing_z.yaml",
     "9:9: beam.section.components[0]: missing required key 'z'",
     NULL},
    {"components_and_nodes.yaml",
     "10:12: beam.section.nodes: give either components or nodes + elements, not both",
     NULL},
    {"constraint_no_kind.yaml",
     "9:5: constraints[0]: must be one of clamp, fix, displacement",
     NULL},
    {"constraint_not_list.yaml",
     "9:3: constraints: must be a list of constraints (clamp, fix, displacement), got a",
     NULL},
    {"constraint_two_kinds.yaml",
     "10:5: constraints[1]: has both 'clamp' and 'fix'; give one of clamp, fix, displacement",
     NULL},
    {"control_char.yaml",
     "1:9: invalid character: control characters are not allowed (byte 0x01)",
     NULL},
    {"coupling_method_typo.yaml",
     "16:11: coupling.method: must be one of fictitious | lagrange | arlequin, got",
     NULL},
    {"coupling_missing.yaml",
     "11:3: coupling: required when the model has both beam and peridynamics; add coupling:",
     NULL},
    {"coupling_without_pd.yaml",
     "11:3: coupling: only meaningful when the model has both beam and peridynamics",
     NULL},
    {"density_negative.yaml",
     "2:39: materials.resin.density: must be >= 0, got -1",
     NULL},
    {"dimension_2.yaml",
     "6:14: peridynamics.dimension: must be 3 or 1 (dimension 2 is not supported), got 2",
     NULL},
    {"dimension_string.yaml",
     "6:14: peridynamics.dimension: must be an integer, got 'three'",
     NULL},
    {"directory_empty.yaml",
     "8:21: output.directory: must not be empty",
     NULL},
    {"displacement_all_null.yaml",
     "9:45: constraints[0].displacement.value: all three components are null (free): nothing",
     NULL},
    {"duplicate_key.yaml",
     "6:3: peridynamics.horizon: duplicate key (first given at line 5)",
     NULL},
    {"duplicate_material.yaml",
     "4:3: materials.resin: duplicate material name (first defined at line 2)",
     NULL},
    {"dynamic_dt_zero.yaml",
     "10:17: analysis.dynamic.dt: must be > 0, got 0",
     NULL},
    {"dynamic_every_zero.yaml",
     "10:46: analysis.dynamic.every: must be an integer >= 1, got 0",
     NULL},
    {"dynamic_in_static.yaml",
     "9:12: analysis.dynamic: is only used with type: dynamic",
     NULL},
    {"dynamic_missing.yaml",
     "9:3: analysis: missing required key 'dynamic' (type dynamic needs dynamic: {dt: ...,",
     NULL},
    {"dynamic_newmark_central.yaml",
     "14:14: analysis.dynamic.newmark: is only used with integrator: newmark",
     NULL},
    {"dynamic_no_density.yaml",
     "2:3: materials.resin: needs a density for a dynamic analysis (it is used by",
     NULL},
    {"E_bool.yaml",
     "2:14: materials.resin.E: must be a number, got 'true'",
     NULL},
    {"E_hex.yaml",
     "2:14: materials.resin.E: must be a number, got '0x3E8'",
     NULL},
    {"E_mapping.yaml",
     "2:14: materials.resin.E: must be a number, got a mapping",
     NULL},
    {"E_overflow.yaml",
     "2:14: materials.resin.E: must be a finite number, got '1e400'",
     NULL},
    {"element_bad.yaml",
     "8:14: beam.section.element: must be one of L4 | L9 | L16, got 'L8'; did you mean 'L4'?",
     NULL},
    {"elements_20_digits.yaml",
     "3:33: beam.axis.elements[0]: must be an integer, got '99999999999999999999'",
     NULL},
    {"elements_count.yaml",
     "5:41: beam.axis.elements: needs one element count per span: 4 breakpoints in y give 3",
     NULL},
    {"elements_fraction.yaml",
     "5:45: beam.axis.elements[1]: must be an integer, got '2.5'",
     NULL},
    {"elements_zero.yaml",
     "5:45: beam.axis.elements[1]: must be an integer from 1 to 100000, got 0",
     NULL},
    {"empty.yaml",
     "1:1: the model file is empty",
     NULL},
    {"expr_bad_number.yaml",
     "9:24: loads[0].body.value[1]: bad expression \"1e+\": malformed number '1e+' at column 1",
     NULL},
    {"expr_div_zero.yaml",
     "9:23: loads[0].body.value[1]: expression '1/0' evaluates to inf",
     NULL},
    {"expr_empty.yaml",
     "9:24: loads[0].body.value[1]: bad expression \"\": empty expression",
     NULL},
    {"expr_nan.yaml",
     "9:23: loads[0].body.value[1]: expression 'sqrt(-1)' evaluates to",
     "nan"},
    {"expr_plain_garbage.yaml",
     "9:48: constraints[0].displacement.value[0]: bad expression \"2 x\": unexpected 'x' at",
     NULL},
    {"expr_too_deep.yaml",
     "9:155: loads[0].body.value[2]: bad expression",
     "nested too deeply (more than 256 levels)"},
    {"expr_too_long.yaml",
     "9:24: loads[0].body.value[1]: bad expression \"x+x+x+x+x+x+x+x+x+x+x+x+x+x+x+x+x+x+x+x+x+",
     "expression too long (4199 characters, at most 4096)"},
    {"expr_trailing_op.yaml",
     "9:27: loads[0].body.value[1]: bad expression \"x +\": missing operand after '+' at column ",
     NULL},
    {"expr_two_args.yaml",
     "9:29: loads[0].body.value[1]: bad expression \"sin(x, y)\": function 'sin' takes one argum",
     "function 'sin' takes one argument"},
    {"expr_unbalanced.yaml",
     "9:29: loads[0].body.value[2]: bad expression \"sin(x\": unbalanced parentheses: '(' at",
     NULL},
    {"expr_unknown_function.yaml",
     "9:24: loads[0].body.value[1]: bad expression \"foo(x)\": unknown name 'foo' at column 1 (a",
     "unknown name 'foo'"},
    {"expr_unknown_name.yaml",
     "9:29: loads[0].body.value[1]: bad expression \"1e-3*q\": unknown name 'q' at column 6",
     "(allowed: x, y, z, t, density, pi; functions sin"},
    {"field_missing.yaml",
     "9:3: analysis: missing required key 'field' (type evaluate imposes field: [ux, uy, uz])",
     NULL},
    {"field_not_evaluate.yaml",
     "10:10: analysis.field: is only used with type: evaluate",
     NULL},
    {"fix_component_bad.yaml",
     "9:45: constraints[0].fix.components[1]: must be one of x | y | z, got 'w'",
     NULL},
    {"fix_component_twice.yaml",
     "9:45: constraints[0].fix.components[1]: component 'x' is listed twice",
     NULL},
    {"flow_duplicate_key.yaml",
     "2:30: materials.resin.E: duplicate key (first given at line 2)",
     NULL},
    {"adaptive_no_fracture.yaml",
     "9:13: peridynamics.adaptive: needs peridynamics.fracture: the zone grows where the beam "
     "nears the critical stretch and follows the cracks",
     NULL},
    {"adaptive_threshold.yaml",
     "10:25: peridynamics.adaptive.threshold: must lie in (0, 1] (a fraction of the critical "
     "stretch s0",
     "got 1.5"},
    {"adaptive_every.yaml", "10:37: peridynamics.adaptive.every: must be an integer >= 1",
     "got 0"},
    {"adaptive_no_beam.yaml",
     "10:13: peridynamics.adaptive: needs a beam: the PD zone grows by turning beam elements into "
     "PD",
     NULL},
    {"adaptive_within_outside.yaml",
     "13:38: peridynamics.adaptive.within: the box y in [120, 140] lies outside the beam (y in "
     "[0, 100]): the zone could never grow",
     NULL},
    {"overlap_empty.yaml",
     "16:38: coupling.arlequin.overlap: lists no slab; give 1 to 32 (one per interface face of "
     "the PD regions; an empty list is for an adaptive zone that starts empty",
     NULL},
    {"adaptive_empty_overlaps.yaml",
     "15:39: coupling.arlequin.overlap[0]: with peridynamics.regions: [] the zone starts empty "
     "and its overlaps span peridynamics.adaptive.overlap horizons each: give overlap: []",
     NULL},
    {"adaptive_overlap_with_regions.yaml",
     "12:62: peridynamics.adaptive.overlap: is the overlap width of a zone that starts empty "
     "(regions: []); a zone that starts with regions keeps the widths of "
     "coupling.arlequin.overlap",
     NULL},
    {"adaptive_overlap_zero.yaml",
     "12:62: peridynamics.adaptive.overlap: must be positive (horizons: the overlaps of a zone "
     "that starts empty span at least this), got 0",
     NULL},
    {"fracture_both_limits.yaml",
     "10:26: peridynamics.fracture.energy_release_rate: give critical_stretch (s0) or "
     "energy_release_rate (G0), not both",
     NULL},
    {"fracture_criterion_bad.yaml",
     "9:16: peridynamics.fracture.criterion: must be one of stretch | energy, got 'strech'; "
     "did you mean 'stretch'?",
     NULL},
    {"fracture_dimension_1.yaml",
     "4:13: peridynamics.fracture: precracks and fracture need dimension: 3",
     NULL},
    {"fracture_energy_bond.yaml",
     "9:16: peridynamics.fracture.criterion: the energy criterion needs model: lps; use "
     "criterion: stretch for bond-based",
     NULL},
    {"fracture_calibration_lps.yaml",
     "11:18: peridynamics.fracture.calibration: grid is defined for model: bond (the energy a cut "
     "releases is the sum of the energies of the bonds it cuts); with lps a cut also releases "
     "the dilatation energy of whole families: use calibration: continuum",
     NULL},
    {"fracture_calibration_s0.yaml",
     "9:52: peridynamics.fracture.calibration: calibrates the critical stretch from "
     "energy_release_rate (G0): it needs criterion: stretch with energy_release_rate, not "
     "critical_stretch",
     NULL},
    /* shapes and holes (issue 35) */
    {"shape_coupled.yaml",
     "15:7: peridynamics.regions[0]: cylinder, sphere and geometry regions need coupling.method: "
     "arlequin with a beam: the fictitious-node and Lagrange couplings build their interfaces "
     "on box regions",
     NULL},
    {"shape_cylinder_axis.yaml",
     "8:25: peridynamics.regions[0].cylinder.axis: must be one of x | y | z, got 'w'", NULL},
    {"shape_cylinder_no_ends.yaml",
     "8:18: peridynamics.regions[0].cylinder: a cylinder region needs both from and to (its ends "
     "along z)",
     NULL},
    {"shape_radius_negative.yaml",
     "8:52: peridynamics.regions[0].cylinder.radius: must be > 0, got -2", NULL},
    {"shape_sphere_center.yaml",
     "8:25: peridynamics.regions[0].sphere.center: must be a list of 3 numbers [x, y, z], got 2 "
     "items",
     NULL},
    {"shape_two_shapes.yaml",
     "8:7: peridynamics.regions[0]: a region is one shape: a box {x, y, z}, or {cylinder: {..}}, "
     "or {sphere: {..}}",
     NULL},
    {"hole_cylinder_one_end.yaml",
     "10:18: peridynamics.holes[0].cylinder: a cylinder hole with either end needs both from and "
     "to (its ends along z)",
     NULL},
    {"hole_empty.yaml",
     "10:7: peridynamics.holes[0]: a hole is a box {x, y, z} (at least one axis), {cylinder: "
     "{..}} or {sphere: {..}}",
     NULL},
    {"geometry_missing.yaml",
     "8:18: peridynamics.regions[0].geometry: ", "no_such_part.step: cannot open it: No such file or directory"},
    {"section_mesh_missing.yaml",
     "9:11: beam.section.mesh: ", "no_such_section.msh: cannot open it: No such file or directory"},
    {"output_exodus_word.yaml", "12:11: output.exodus: must be true or false, got 'exo'", NULL},
    {"output_checkpoint_negative.yaml",
     "13:15: output.checkpoint: must be seconds between checkpoints, from 0 (none) to 1e9",
     NULL},
    {"fracture_calibration_bad.yaml",
     "9:53: peridynamics.fracture.calibration: must be one of continuum | grid, got 'lattice'",
     NULL},
    {"fracture_energy_no_g0.yaml",
     "9:5: peridynamics.fracture: missing required key 'energy_release_rate' (criterion "
     "energy needs G0)",
     NULL},
    {"fracture_energy_s0.yaml",
     "11:23: peridynamics.fracture.critical_stretch: is not used with criterion: energy (the "
     "critical bond energy comes from energy_release_rate, G0)",
     NULL},
    {"fracture_g0_overflow.yaml",
     "8:35: peridynamics.fracture.energy_release_rate: must be a finite number, got '1e400'",
     NULL},
    {"evaluate_time.yaml",
     "9:11: analysis: value[1] \"1e-3*y*t\" uses t, the time of a dynamic analysis; analysis "
     "type: evaluate has no time (it evaluates one field: give it without t)",
     NULL},
    {"static_time_prescribed.yaml",
     "11:5: constraints[1]: value[1] \"0.01*t\" uses t, the time of a dynamic analysis; "
     "analysis type: static has no time",
     NULL},
    {"static_time_beam_traction.yaml",
     "15:5: loads[0]: value[1] \"100*t\" uses t, the time of a dynamic analysis",
     NULL},
    {"no_fail_zero_volume.yaml",
     "11:29: peridynamics.fracture.no_fail[1]: the box has no volume along x ([5, 5])",
     NULL},
    {"per_iteration_dynamic.yaml",
     "9:55: peridynamics.fracture.per_iteration: is only used with type: static",
     NULL},
    {"fracture_no_limit.yaml",
     "9:5: peridynamics.fracture: missing required key: give critical_stretch (s0) or "
     "energy_release_rate (G0)",
     NULL},
    {"fracture_not_map.yaml",
     "8:13: peridynamics.fracture: must be a mapping (key: value), got 'stretch'",
     NULL},
    {"fracture_per_iteration_bad.yaml",
     "10:20: peridynamics.fracture.per_iteration: must be one of all | one, got 'every'",
     NULL},
    {"fracture_s0_zero.yaml",
     "8:32: peridynamics.fracture.critical_stretch: must be > 0, got 0",
     NULL},
    {"fracture_unknown_key.yaml",
     "10:5: peridynamics.fracture.no_fial: unknown key; did you mean 'no_fail'?",
     NULL},
    {"horizon_negative.yaml",
     "5:12: peridynamics.horizon: must be larger than spacing (1), got -3",
     NULL},
    {"horizon_small.yaml",
     "5:12: peridynamics.horizon: must be larger than spacing (1), got 0.5",
     NULL},
    {"horizon_with_unit.yaml",
     "5:12: peridynamics.horizon: must be a number, got '3 mm'",
     NULL},
    {"integration_bad.yaml",
     "10:16: beam.integration: must be one of full | reduced | mitc, got 'MITC'; did you mean",
     NULL},
    {"isotropic_with_G.yaml",
     "2:33: materials.resin.G: G is only used by orthotropic materials (E: [Ex, Ey, Ez]); an",
     NULL},
    {"key_not_scalar.yaml",
     "8:3: keys must be plain names, got a list",
     NULL},
    {"latin1.yaml",
     "1:11: not valid UTF-8 text: invalid trailing UTF-8 octet",
     NULL},
    {"le_no_element.yaml",
     "7:5: beam.section: missing required key 'element': expansion LE needs element: L4 | L9",
     NULL},
    {"line_name_bad.yaml",
     "10:14: output.lines[0].name: must be a name of letters, digits, _ and - (it is used in",
     NULL},
    {"line_name_dup.yaml",
     "12:7: output.lines[2].name: duplicate line name 'a' (also output.lines[0])",
     NULL},
    {"line_name_empty.yaml",
     "10:14: output.lines[0].name: must be a name of letters, digits, _ and - (it is used in f",
     NULL},
    {"line_points_one.yaml",
     "10:57: output.lines[0].points: must be an integer from 2 to 10000000, got 1",
     NULL},
    {"line_zero_length.yaml",
     "10:38: output.lines[0].to: must differ from 'from' (a line needs two distinct ends)",
     NULL},
    {"load_null.yaml",
     "9:36: loads[0].point.value[0]: must be a number or an expression, got null (null, a",
     NULL},
    {"load_two_values.yaml",
     "9:30: loads[0].traction.value: must be a list of 3 values [vx, vy, vz] (numbers or",
     NULL},
    {"loads_mapping.yaml",
     "8:8: loads: must be a list of loads (traction, point, body), got a mapping",
     NULL},
    {"lps_1d.yaml",
     "7:10: peridynamics.model: LPS needs dimension 3; use model: bond with dimension: 1",
     NULL},
    {"materials_empty.yaml",
     "1:12: materials: must define at least one material",
     NULL},
    {"materials_list.yaml",
     "2:3: materials: must be a mapping of material names to {E: ..., nu: ...}, got a list",
     NULL},
    {"materials_null.yaml",
     "1:11: materials: must be a mapping of material names to {E: ..., nu: ...}, got null",
     NULL},
    {"merge_key.yaml",
     "3:11: materials.steel.<<: unknown key; allowed keys here: E, nu, G, density",
     NULL},
    {"missing_horizon.yaml",
     "4:3: peridynamics: missing required key 'horizon'",
     NULL},
    {"missing_materials.yaml",
     "1:1: missing required key 'materials'",
     NULL},
    {"model_typo.yaml",
     "6:10: peridynamics.model: must be one of lps | bond, got 'lsp'; did you mean 'lps'?",
     NULL},
    {"multi_doc.yaml",
     "8:1: the file holds more than one YAML document ('---'); a model file holds exactly one",
     NULL},
    {"negative_E.yaml",
     "2:14: materials.resin.E: must be > 0, got -5",
     NULL},
    {"nested_unknown_key.yaml",
     "5:3: peridynamics.horizn: unknown key; did you mean 'horizon'?",
     NULL},
    {"no_beam_no_pd.yaml",
     "1:1: a model needs a beam: section, a peridynamics: section, or both",
     NULL},
    {"no_fail_empty_box.yaml",
     "11:9: peridynamics.fracture.no_fail[0]: a box needs at least one of x, y, z, each [min, "
     "max]",
     NULL},
    {"no_fail_not_list.yaml",
     "10:14: peridynamics.fracture.no_fail: must be a list of boxes {x: [..], y: [..], z: "
     "[..]}, got a mapping",
     NULL},
    {"no_fail_outside.yaml",
     "12:9: peridynamics.fracture.no_fail[1]: no_fail box lies outside the body (it overlaps "
     "no PD region)",
     NULL},
    {"no_fail_too_many.yaml",
     "10:14: peridynamics.fracture.no_fail: lists 33 boxes, at most 32 are allowed",
     NULL},
    {"not_utf8.yaml",
     "1:11: not valid UTF-8 text: invalid trailing UTF-8 octet",
     NULL},
    {"nu_half.yaml",
     "2:25: materials.resin.nu: must satisfy -1 < nu < 0.5, got 0.5",
     NULL},
    {"nu_minus_one.yaml",
     "2:24: materials.resin.nu: must satisfy -1 < nu < 0.5, got -1",
     NULL},
    {"nul_byte.yaml",
     "1:9: invalid character: control characters are not allowed (byte 0x00)",
     NULL},
    {"only_bom.yaml",
     "1:1: the model file is empty",
     NULL},
    {"orthotropic_bad_nu.yaml",
     "2:36: materials.ply.nu: these Poisson ratios with E = [1000, 1000, 1000] give a",
     NULL},
    {"orthotropic_no_G.yaml",
     "2:8: materials.ply: missing required key 'G' (an orthotropic material needs G: [Gxy,",
     NULL},
    {"overlong_utf8.yaml",
     "1:8: not valid UTF-8 text: invalid length of a UTF-8 sequence",
     NULL},
    {"peridynamics_list.yaml",
     "3:15: peridynamics: must be a mapping (key: value), got a list",
     NULL},
    {"point_at_short.yaml",
     "9:17: loads[0].point.at: must be a list of 3 numbers [x, y, z], got 2 items",
     NULL},
    {"point_name_dup.yaml",
     "11:7: output.points[1].name: duplicate point name 'tip' (also output.points[0])",
     NULL},
    {"points_int_overflow.yaml",
     "10:57: output.lines[0].points: must be an integer from 2 to 10000000, got 2147483648",
     NULL},
    {"poisson_correction_bad.yaml",
     "10:23: beam.poisson_correction: must be one of auto | on | off, got 'true'",
     NULL},
    {"poisson_correction_te2.yaml",
     "10:23: beam.poisson_correction: 'on' applies to TE0 and TE1 only: TE2 and higher sections "
     "contract freely",
     NULL},
    {"precrack_at_missing.yaml",
     "9:7: peridynamics.precracks[0]: missing required key 'at' (the position of the crack "
     "plane along y)",
     NULL},
    {"precrack_at_string.yaml",
     "9:23: peridynamics.precracks[0].at: must be a number, got 'middle'",
     NULL},
    {"precrack_normal_bad.yaml",
     "9:16: peridynamics.precracks[0].normal: must be one of x | y | z, got 'Y'; did you mean "
     "'y'?",
     NULL},
    {"precrack_normal_bounds.yaml",
     "9:41: peridynamics.precracks[0].y: is the crack's normal axis: the crack lies on the "
     "plane y = at and takes bounds on x and z only",
     NULL},
    {"precrack_normal_missing.yaml",
     "9:7: peridynamics.precracks[0]: missing required key 'normal' (x, y or z: the axis "
     "normal to the crack)",
     NULL},
    {"precrack_not_map.yaml",
     "9:7: peridynamics.precracks[0]: must be a mapping (key: value), got a list",
     NULL},
    {"precrack_outside_plane.yaml",
     "10:7: peridynamics.precracks[1]: lies outside every PD region (none of them reaches y = "
     "25)",
     NULL},
    {"precrack_outside_rect.yaml",
     "9:7: peridynamics.precracks[0]: lies outside every PD region (on the plane x = 5, the "
     "rectangle y [0, 20], z [4, 8] overlaps none of them)",
     NULL},
    {"precrack_reversed.yaml",
     "9:40: peridynamics.precracks[0].y: must be [min, max] with min < max, got [12, 8]",
     NULL},
    {"precrack_side_missing.yaml",
     "9:7: peridynamics.precracks[0]: missing required key 'z' (a precrack with normal y "
     "needs x: [min, max] and z: [min, max])",
     NULL},
    {"precrack_unknown_key.yaml",
     "9:8: peridynamics.precracks[0].nromal: unknown key; did you mean 'normal'?",
     NULL},
    {"precrack_zero_size.yaml",
     "9:30: peridynamics.precracks[0].x: must be [min, max] with min < max, got [4, 4] (the "
     "rectangle has zero size)",
     NULL},
    {"precracks_dimension_1.yaml",
     "11:5: peridynamics.precracks: precracks and fracture need dimension: 3",
     NULL},
    {"precracks_not_list.yaml",
     "8:14: peridynamics.precracks: must be a list of rectangles {normal: y, at: 50, x: [..], "
     "z: [..]}, got a mapping",
     NULL},
    {"recursive_alias.yaml",
     "8:9: nested more than 64 levels deep (or an alias refers to itself)",
     NULL},
    {"region_1d_with_x.yaml",
     "9:23: peridynamics.regions[0].x: dimension 1 regions take only y: [y0, y1] (a bar along",
     NULL},
    {"region_bound_string.yaml",
     "7:15: peridynamics.regions[0].x[1]: must be a number, got 'a'",
     NULL},
    {"region_inverted.yaml",
     "7:11: peridynamics.regions[0].x: must be [min, max] with min < max, got [10, 0]",
     NULL},
    {"region_missing_z.yaml",
     "7:7: peridynamics.regions[0]: missing required key 'z' (a region needs x, y and z, each",
     "a region needs x, y and z"},
    {"region_nan_bound.yaml",
     "7:12: peridynamics.regions[0].x[0]: must be a number, got '.nan'",
     NULL},
    {"region_three_numbers.yaml",
     "7:11: peridynamics.regions[0].x: must be a list of 2 numbers [min, max], got 3 items",
     NULL},
    {"regions_empty.yaml",
     "2:49: peridynamics.regions: must list at least one region",
     NULL},
    {"section_element_count.yaml",
     "10:9: beam.section.elements[0]: an L9 element needs 9 node indices, got 4",
     NULL},
    {"section_index_range.yaml",
     "10:19: beam.section.elements[0][3]: node index must be from 0 to 3 (indices into",
     NULL},
    {"simple_key_too_long.yaml",
     "1:2001: YAML syntax error: mapping values are not allowed in this context",
     NULL},
    {"fictitious_fe_unknown.yaml",
     "28:47: coupling.fictitious_fe: must be one of removed | adjacent | plane, got 'half'", NULL},
    {"balance_unknown.yaml",
     "28:41: coupling.balance: must be one of none | momentum | global, got 'yes'", NULL},
    {"balance_lagrange.yaml",
     "28:39: coupling.balance: is only used with method: fictitious (lagrange and arlequin "
     "conserve momentum already)", NULL},
    {"solver_typo.yaml",
     "9:11: analysis.solver: must be one of auto | direct | petsc | krylov, got 'Direct'; did you mean",
     NULL},
    {"spacing_nan.yaml",
     "4:12: peridynamics.spacing: must be a number, got '.nan'",
     NULL},
    {"spacing_string.yaml",
     "4:12: peridynamics.spacing: must be a number, got 'abc'",
     NULL},
    {"spacing_zero.yaml",
     "4:12: peridynamics.spacing: must be > 0, got 0",
     NULL},
    {"stress_not_bool.yaml",
     "10:40: output.points[0].stress: must be true or false, got '1'",
     NULL},
    {"surrogate_utf8.yaml",
     "1:9: not valid UTF-8 text: invalid Unicode character (byte 0xd800)",
     NULL},
    {"syntax_indent.yaml",
     "5:11: YAML syntax error: mapping values are not allowed in this context",
     NULL},
    {"syntax_unclosed.yaml",
     "4:1: YAML syntax error: did not find expected ',' or '}' (while parsing a flow mapping)",
     NULL},
    {"tab_indent.yaml",
     "4:1: YAML syntax error: found character that cannot start any token (while scanning for",
     "YAML does not allow tabs for indentation, use spaces"},
    {"te_too_high.yaml",
     "7:16: beam.section.expansion: TE order must be at most 20, got 99",
     NULL},
    {"title_list.yaml",
     "1:8: title: must be a string, got a list",
     NULL},
    {"top_duplicate_section.yaml",
     "8:1: materials: duplicate key (first given at line 1)",
     NULL},
    {"top_list.yaml",
     "1:1: the top level of a model must be a mapping of sections (title:, materials:, beam:,",
     NULL},
    {"top_scalar.yaml",
     "1:1: the top level of a model must be a mapping of sections (title:, materials:, beam:,",
     NULL},
    {"top_unknown_close.yaml",
     "1:1: materails: unknown key; did you mean 'materials'?",
     NULL},
    {"top_unknown_far.yaml",
     "8:1: solver_settings: unknown key; allowed keys here: title, materials, beam,",
     "allowed keys here: title, materials, beam, peridynamics"},
    {"traction_patch_inverted.yaml",
     "9:26: loads[0].traction.x: must be [min, max] with min < max, got [5, 5]",
     NULL},
    {"undefined_alias.yaml",
     "9:5: YAML syntax error: found undefined alias",
     NULL},
    {"unknown_material_close.yaml",
     "6:13: peridynamics.material: unknown material 'resn'; did you mean 'resin'?",
     NULL},
    {"unknown_material_far.yaml",
     "7:13: peridynamics.material: unknown material 'aluminium'; known materials: resin, steel",
     "known materials: resin, steel"},
    {"unterminated_quote.yaml",
     "8:1: YAML syntax error: found unexpected end of stream (while scanning a quoted scalar)",
     NULL},
    {"utf16_bom.yaml",
     "2:12: materials: must be a mapping of material names to {E: ..., nu: ...}, got a list",
     NULL},
    {"windows_1252_quotes.yaml",
     "1:8: not valid UTF-8 text: invalid leading UTF-8 octet (byte 0x93)",
     NULL},
    {"yaml_version_2.yaml",
     "1:1: YAML syntax error: found incompatible YAML document",
     NULL},
};
static const int n_cases = (int)(sizeof cases / sizeof *cases);

static void test_catalogue(void **state) {
  (void)state;
  for (int i = 0; i < n_cases; i++) {
    char rel[256], want[512];
    snprintf(rel, sizeof rel, "tests/models/bad/%s", cases[i].file);
    cupid_model m = (cupid_model)1;
    cupid_status st = cupid_model_read(cupid_test_source_path(rel), &m);
    if (st != CUPID_ERR_MODEL)
      fail_msg("%s: status %d (%s), expected a model error", cases[i].file, st,
               cupid_error_message());
    assert_null(m);
    /* The file name as given, then exactly the expected position, key and message. */
    snprintf(want, sizeof want, "/%s:%s", cases[i].file, cases[i].expected);
    if (!strstr(cupid_error_message(), want))
      fail_msg("%s:\n  got      '%s'\n  expected '...%s...'", cases[i].file, cupid_error_message(),
               want);
    if (cases[i].also && !strstr(cupid_error_message(), cases[i].also))
      fail_msg("%s: '%s' lacks '%s'", cases[i].file, cupid_error_message(), cases[i].also);
  }
  print_message("%d malformed models rejected at the expected position\n", n_cases);
}

/* Every file in tests/models/bad/ has its row in the table (no case goes unchecked). */
static void test_catalogue_complete(void **state) {
  (void)state;
  DIR *dir = opendir(cupid_test_source_path("tests/models/bad"));
  assert_non_null(dir);
  int files = 0;
  for (struct dirent *e; (e = readdir(dir));) {
    if (e->d_name[0] == '.') continue;
    files++;
    int found = 0;
    for (int i = 0; i < n_cases && !found; i++) found = !strcmp(cases[i].file, e->d_name);
    if (!found) fail_msg("tests/models/bad/%s has no entry in the table", e->d_name);
  }
  closedir(dir);
  assert_int_equal(files, n_cases);
  assert_true(n_cases >= 40);
}

static void test_io_errors(void **state) {
  (void)state;
  cupid_model m = (cupid_model)1;
  assert_int_equal(cupid_model_read("no/such/model.yaml", &m), CUPID_ERR_IO);
  assert_null(m);
  assert_non_null(strstr(cupid_error_message(), "no/such/model.yaml"));
  assert_non_null(strstr(cupid_error_message(), "No such file or directory"));
  /* A directory opens on Linux but cannot be read. */
  assert_int_equal(cupid_model_read(cupid_test_source_path("tests/models/bad"), &m), CUPID_ERR_IO);
  assert_null(m);
  /* An endless input stops at the size limit (16 MiB) instead of filling memory. */
  assert_int_equal(cupid_model_read("/dev/zero", &m), CUPID_ERR_MODEL);
  assert_string_equal(cupid_error_message(),
                      "/dev/zero:1:1: the model file is too large (more than 16 MiB)");
  assert_int_equal(cupid_model_read(NULL, &m), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_model_read_string("", 0, "x.yaml", NULL), CUPID_ERR_ARGUMENT);
}

static cupid_status read_text(const char *text, size_t length) {
  cupid_model m = NULL;
  cupid_status st = cupid_model_read_string(text, length, "mem.yaml", &m);
  if (st == CUPID_SUCCESS) assert_non_null(m);
  else assert_null(m);
  cupid_model_destroy(&m);
  return st;
}

static void expect(const char *text, const char *fragment) {
  cupid_status st = read_text(text, strlen(text));
  if (st != CUPID_ERR_MODEL || !strstr(cupid_error_message(), fragment))
    fail_msg("status %d, message '%s', expected '%s'", st, cupid_error_message(), fragment);
}

#define PD "peridynamics: {spacing: 1, horizon: 3, regions: [{x: [0, 1], y: [0, 1], z: [0, 1]}]}\n"
#define MAT "materials: {m: {E: 1, nu: 0.2}}\n"

static void test_limits(void **state) {
  (void)state;
  assert_int_equal(read_text(NULL, 0), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "mem.yaml:1:1: the model file is empty"));
  expect("---\n", "mem.yaml:1:1: the model file is empty");
  /* Deep nesting and self-reference fail fast instead of exhausting the stack. */
  char *deep = malloc(2400000);
  assert_non_null(deep);
  int n = sprintf(deep, "title: ");
  for (int i = 0; i < 100000; i++) deep[n++] = '[';
  for (int i = 0; i < 100000; i++) deep[n++] = ']';
  deep[n] = '\0';
  expect(deep, "mem.yaml:1:72: nested more than 64 levels deep");
  /* A flat list of 1.1 million items exceeds the node bound before any section is read. */
  n = sprintf(deep, MAT PD "loads: [");
  for (int i = 0; i < 1100000; i++) n += sprintf(deep + n, "1,");
  strcpy(deep + n, "1]\n");
  expect(deep, "model too large (more than 1000000 values)");
  /* Billion laughs, deeper than the file's: 10^12 nodes if expanded. */
  n = sprintf(deep, MAT PD "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n");
  for (int i = 1; i < 12; i++) {
    n += sprintf(deep + n, "a%d: &a%d [", i, i);
    for (int j = 0; j < 10; j++) n += sprintf(deep + n, "*a%d%s", i - 1, j < 9 ? ", " : "]\n");
  }
  double t0 = cupid_wtime();
  expect(deep, "model too large or alias expansion too deep");
  /* The bound is 10^6 node visits: well under a second even on a slow machine. */
  assert_true(cupid_wtime() - t0 < 1.0);
  /* Over-long strings. */
  n = sprintf(deep, MAT PD "title: ");
  for (int i = 0; i < 5000; i++) deep[n++] = 'a';
  deep[n] = '\0';
  expect(deep, "mem.yaml:3:8: title: is too long (5000 bytes, at most 4096)");
  free(deep);
  expect(MAT PD "title: \"a\\0b\"\n", "mem.yaml:3:8: title: must not contain NUL characters");
  expect(MAT PD "loads: [{point: {at: [0, 0, 0], value: [0, 0, \"1/0\"]}}]\n",
         "mem.yaml:3:47: loads[0].point.value[2]: expression '1/0' evaluates to inf");
  expect(MAT PD "loads: [{point: {at: [0, 0, .inf], value: [0, 0, 1]}}]\n",
         "loads[0].point.at[2]: must be a number, got '.inf'");
}

/* At most 1000 precracks: each is checked against every region here and every bond later. */
static void test_precrack_limit(void **state) {
  (void)state;
  char *text = malloc(64000);
  assert_non_null(text);
  for (int count = 1000; count <= 1001; count++) {
    int n = sprintf(text, MAT "peridynamics:\n  spacing: 1\n  horizon: 3\n"
                              "  regions: [{x: [0, 4], y: [0, 4], z: [0, 4]}]\n"
                              "  precracks: [&c {normal: y, at: 2, x: [0, 1], z: [0, 1]}");
    for (int i = 1; i < count; i++) n += sprintf(text + n, ", *c");
    strcpy(text + n, "]\n");
    if (count == 1000) assert_int_equal(read_text(text, strlen(text)), CUPID_SUCCESS);
    else expect(text, "mem.yaml:6:14: peridynamics.precracks: lists 1001 precracks, at most 1000");
  }
  free(text);
}

/* Random mutations of the valid models: the reader must return success or a model error with
 * a position, never crash, hang or leak (run under valgrind or ASan to check the last two). */
static void test_mutations(void **state) {
  (void)state;
  static const char *const good[] = {"bar.yaml",         "pd_only.yaml",    "truss_1d.yaml",
                                     "le_explicit.yaml", "components.yaml", "fracture.yaml"};
  static const char *const snippets[] = {"[", "]", "{", "}", ":", ",", "- ", "&a ", "*a", "\t",
                                         "\n", "\"", "'", "null", "-1", "1e999", "x", "#", "? ",
                                         "\xff", "\xc3", "---\n", "!!str ", "  "};
  uint64_t seed = 2024;
  int accepted = 0, rejected = 0;
  for (int g = 0; g < (int)(sizeof good / sizeof *good); g++) {
    char rel[256];
    snprintf(rel, sizeof rel, "tests/models/good/%s", good[g]);
    FILE *f = fopen(cupid_test_source_path(rel), "rb");
    assert_non_null(f);
    char original[8192];
    size_t length = fread(original, 1, sizeof original, f);
    fclose(f);
    char text[8192 + 64];
    for (int iter = 0; iter < 600; iter++) {
      memcpy(text, original, length);
      size_t n = length;
      int edits = 1 + (int)((cupid_test_random(&seed) + 1) * 2);
      for (int e = 0; e < edits; e++) {
        size_t at = (size_t)((cupid_test_random(&seed) + 1) / 2 * (double)n);
        if (at >= n) at = n - 1;
        double kind = cupid_test_random(&seed);
        if (kind < -0.5) { /* overwrite a byte */
          text[at] = (char)(int)((cupid_test_random(&seed) + 1) * 128);
        } else if (kind < 0) { /* delete a byte */
          memmove(text + at, text + at + 1, n - at - 1);
          n--;
        } else if (kind < 0.8) { /* insert a snippet */
          int s = (int)((cupid_test_random(&seed) + 1) / 2 * 24);
          size_t k = strlen(snippets[s < 24 ? s : 23]);
          if (n + k >= sizeof text) continue;
          memmove(text + at + k, text + at, n - at);
          memcpy(text + at, snippets[s < 24 ? s : 23], k);
          n += k;
        } else { /* truncate */
          n = at + 1;
        }
      }
      cupid_status st = read_text(text, n);
      if (st == CUPID_SUCCESS) {
        accepted++;
      } else {
        rejected++;
        if (st != CUPID_ERR_MODEL)
          fail_msg("mutation gave status %d: %s", st, cupid_error_message());
        /* Every model error names the file and a position. */
        if (strncmp(cupid_error_message(), "mem.yaml:", 9))
          fail_msg("message without position: %s", cupid_error_message());
      }
    }
  }
  print_message("mutations: %d accepted, %d rejected\n", accepted, rejected);
  assert_true(rejected > 0 && accepted > 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_catalogue),
      cmocka_unit_test(test_catalogue_complete),
      cmocka_unit_test(test_io_errors),
      cmocka_unit_test(test_limits),
      cmocka_unit_test(test_precrack_limit),
      cmocka_unit_test(test_mutations),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

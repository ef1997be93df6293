/* A C program that runs a cupid model through the library (include/cupid/problem.h) and prints
 * what it read back as JSON: counts, the solver, the resultants, the displacement at the model's
 * output points and the largest PD and beam displacements.
 *
 *   cc run_model.c $(pkg-config --cflags --libs cupid) -o run_model
 *   ./run_model MODEL.yaml [OUTPUT_DIR]
 *
 * With OUTPUT_DIR it also writes the model's output files there, as `cupid run -o` does.
 * tests/regression/library.sh builds it against the installed library and checks that every
 * number equals the command line's summary.json. */
#include <math.h>
#include <stdio.h>

#include <cupid.h>

static int fail(cupid_status st, const char *what) {
  fprintf(stderr, "run_model: %s: %s: %s\n", what, cupid_status_name(st), cupid_error_message());
  return cupid_status_exit_code(st);
}

/* The largest |u| over the rows of a field of 3 components. */
static double max_norm(const double *u, cupid_int n) {
  double m = 0.0;
  for (cupid_int i = 0; i < n; i++)
    m = fmax(m, sqrt(u[3 * i] * u[3 * i] + u[3 * i + 1] * u[3 * i + 1] + u[3 * i + 2] * u[3 * i + 2]));
  return m;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: run_model MODEL.yaml [OUTPUT_DIR]\n");
    return 1;
  }
  cupid_run_options opts = cupid_run_options_default();
  opts.quiet = 1;
  opts.output_dir = argc > 2 ? argv[2] : NULL;
  cupid_problem p = NULL;
  cupid_status st = cupid_problem_create_from_file(argv[1], &opts, &p);
  if (st == CUPID_SUCCESS) st = cupid_problem_setup(p);
  if (st == CUPID_SUCCESS) st = cupid_problem_solve(p);
  if (st == CUPID_SUCCESS && argc > 2) st = cupid_problem_write_outputs(p);
  if (st != CUPID_SUCCESS) {
    int code = fail(st, argv[1]);
    cupid_problem_destroy(&p);
    return code;
  }

  cupid_problem_info info;
  const double *u_pd, *u_beam;
  cupid_int n_pd, n_beam;
  int nc;
  cupid_problem_get_info(p, &info);
  cupid_problem_get_field(p, CUPID_FIELD_PD_DISPLACEMENT, &u_pd, &n_pd, &nc);
  cupid_problem_get_field(p, CUPID_FIELD_BEAM_DISPLACEMENT, &u_beam, &n_beam, &nc);
  printf("{\n  \"coupling\": \"%s\", \"solver\": \"%s\", \"method\": \"%s\",\n", info.coupling,
         info.solver, info.method);
  printf("  \"pd_nodes\": %lld, \"bonds\": %lld, \"fictitious_nodes\": %lld, \"fe_dofs\": %lld, "
         "\"dofs\": %lld, \"constrained_dofs\": %lld,\n",
         (long long)info.pd_nodes, (long long)info.bonds, (long long)info.fictitious_nodes,
         (long long)info.fe_dofs, (long long)info.dofs, (long long)info.constrained_dofs);
  printf("  \"applied_load_sum\": [%.17g, %.17g, %.17g],\n", info.load_sum[0], info.load_sum[1],
         info.load_sum[2]);
  printf("  \"reaction_sum\": [%.17g, %.17g, %.17g],\n", info.reaction_sum[0],
         info.reaction_sum[1], info.reaction_sum[2]);
  printf("  \"pd_field_rows\": %lld, \"max_pd_displacement\": %.17g,\n", (long long)n_pd,
         max_norm(u_pd, n_pd));
  printf("  \"beam_points\": %lld, \"max_beam_displacement\": %.17g,\n", (long long)n_beam,
         max_norm(u_beam, n_beam));
  printf("  \"points\": [");
  const cupid_model_t *m = cupid_problem_model(p);
  for (int k = 0; k < m->output.n_points; k++) {
    const cupid_output_point *pt = &m->output.points[k];
    double u[3];
    int region;
    cupid_problem_sample(p, 1, pt->at, u, NULL, &region);
    printf("%s\n    {\"name\": \"%s\", \"ux\": %.17g, \"uy\": %.17g, \"uz\": %.17g, \"region\": %d}",
           k ? "," : "", pt->name, u[0], u[1], u[2], region);
  }
  printf("\n  ]\n}\n");
  cupid_problem_destroy(&p);
  return 0;
}

/* Libraries loaded when a model first needs them (io_internal.h, cupid_io_load_library): Gmsh
 * (meshes and CAD files) and Exodus II (model.exo) bring dozens of shared libraries that every
 * start of cupid would pay for when linked. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>

#include "io_internal.h"

int cupid_io_load_library(const char *env, const char *soname, const char *devname,
                          const cupid_io_symbol *syms, size_t n_syms, const char *what,
                          const char *package, char *why, size_t size) {
  const char *given = getenv(env);
  const int own = given && given[0];
  void *h = dlopen(own ? given : soname, RTLD_NOW | RTLD_LOCAL);
  if (!h && !own) h = dlopen(devname, RTLD_NOW | RTLD_LOCAL);
  if (!h) {
    snprintf(why, size, "%s is not installed (Debian's %s; scripts/install-deps.sh installs "
             "it): %s", what, package, dlerror());
    return 0;
  }
  for (size_t k = 0; k < n_syms; k++) {
    *syms[k].fn = dlsym(h, syms[k].name);
    if (!*syms[k].fn) {
      snprintf(why, size, "%s has no %s (another version than cupid needs)", what, syms[k].name);
      return 0;
    }
  }
  return 1; /* kept for the process's life */
}

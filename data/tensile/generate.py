#!/usr/bin/env python3
"""Regenerates tpu-coated-nylon.csv: the uniaxial engineering stress of the seed study's fitted
Yeoh constants plus a small deterministic noise. Synthesised, not measured (see README.md).

    python3 data/tensile/generate.py > data/tensile/tpu-coated-nylon.csv
"""
import math

# Seed study, Table 2 (Yeoh, Abaqus fit of its tensile test) [MPa]
C10, C20, C30 = 31.587917, -0.76582566, -3.06587618
NOISE_SD = 0.15          # [MPa] standard deviation of the added noise
STEP, POINTS = 0.005, 101  # strain 0 to 0.50


def yeoh_nominal_stress(strain):
    """P = 2 (l - l^-2) (C10 + 2 C20 x + 3 C30 x^2), x = I1 - 3 = l^2 + 2/l - 3 [MPa]."""
    l = 1.0 + strain
    x = l * l + 2.0 / l - 3.0
    return 2.0 * (l - 1.0 / (l * l)) * (C10 + 2.0 * C20 * x + 3.0 * C30 * x * x)


class Lcg:
    """Numerical Recipes 32-bit LCG, so the noise does not depend on a library's generator."""

    def __init__(self, seed):
        self.state = seed

    def uniform(self):  # in (0, 1)
        self.state = (1664525 * self.state + 1013904223) % 2**32
        return (self.state + 0.5) / 2**32


def main():
    rng = Lcg(20240229)
    print("# Uniaxial tensile curve of a TPU-coated 840D nylon airbag film.")
    print("# SYNTHESISED, NOT MEASURED: engineering stress of the seed study's fitted Yeoh")
    print("# constants (C10 = 31.587917, C20 = -0.76582566, C30 = -3.06587618 MPa) over")
    print("# 0-50 % strain, plus deterministic Gaussian noise (sd 0.15 MPa; Box-Muller on a")
    print("# 32-bit LCG, seed 20240229; none on the first point). Regenerate with")
    print("# data/tensile/generate.py. See data/tensile/README.md.")
    print("strain,stress_MPa")
    for i in range(POINTS):
        strain = i * STEP
        u1, u2 = rng.uniform(), rng.uniform()
        noise = NOISE_SD * math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)
        stress = yeoh_nominal_stress(strain) + (noise if i > 0 else 0.0)
        print(f"{strain:.3f},{stress:.4f}")


if __name__ == "__main__":
    main()

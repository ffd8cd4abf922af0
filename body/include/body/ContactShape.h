#pragma once
/// @file Convex analytic contact shapes fixed on a body segment: an ellipsoid or a round cone
/// (two spheres joined by their tangent cone; a capsule when the radii are equal).
///
/// What a contact model needs from a shape, answered analytically (no Simbody calls, no
/// meshes): the signed distance of a query point to the surface (negative inside), the closest
/// surface point and the outward unit normal there; the support point (the surface point
/// furthest in a direction, i.e. the deepest point against a plane); and a sampling of the
/// surface into small patches (point, normal, area) for elastic-foundation contact.
/// All points and directions are in the frame of the body the shape is fixed to.

#include <SimTKcommon.h>

#include <vector>

namespace body {

/// Result of a surface query.
struct SurfaceQuery {
    double distance = 0;          ///< signed distance to the surface, negative inside [m]
    SimTK::Vec3 closestPoint{0};  ///< closest surface point, body frame [m]
    SimTK::Vec3 normal{0};        ///< outward unit normal at the closest point, body frame
};

/// A small patch of a shape's surface.
struct SurfaceSample {
    SimTK::Vec3 p_B{0};  ///< patch centre, body frame [m]
    SimTK::Vec3 n_B{0};  ///< outward unit normal, body frame
    double area = 0;     ///< patch area [m^2]
};

/// An ellipsoid or a round cone fixed on a body.
class ContactShape {
  public:
    /// Kind of the shape.
    enum class Kind { Ellipsoid, RoundCone };

    /// Ellipsoid with semi-axes along the axes of R_BS, centred at p_BS.
    /// @throws std::invalid_argument if a semi-axis is not positive.
    static ContactShape makeEllipsoid(const SimTK::Vec3& semiAxes, const SimTK::Vec3& p_BS,
                                      const SimTK::Rotation& R_BS = SimTK::Rotation());
    /// Round cone: sphere of radius rA at pA, sphere of radius rB at pB, and their common
    /// tangent cone. @throws std::invalid_argument unless |pB - pA| > |rA - rB| and radii > 0.
    static ContactShape makeRoundCone(const SimTK::Vec3& pA, double rA, const SimTK::Vec3& pB,
                                      double rB);

    /// Kind of the shape.
    Kind getKind() const { return m_kind; }
    /// Ellipsoid semi-axes in the shape frame [m].
    const SimTK::Vec3& getSemiAxes() const { return m_semiAxes; }
    /// Pose of the ellipsoid's frame in the body frame.
    const SimTK::Transform& getEllipsoidPose() const { return m_X_BS; }
    /// Round cone sphere centres (body frame) [m] and radii [m].
    const SimTK::Vec3& getPointA() const { return m_pA; }
    const SimTK::Vec3& getPointB() const { return m_pB; }  ///< second sphere centre [m]
    double getRadiusA() const { return m_rA; }             ///< first radius [m]
    double getRadiusB() const { return m_rB; }             ///< second radius [m]

    /// Centre [m] and radius [m] of a sphere that encloses the shape (body frame).
    const SimTK::Vec3& getBoundingCentre() const { return m_boundCentre; }
    double getBoundingRadius() const { return m_boundRadius; }  ///< bounding sphere radius [m]

    /// Signed distance, closest point and normal for a query point p_B (body frame).
    SurfaceQuery calcSurfaceQuery(const SimTK::Vec3& p_B) const;
    /// Signed distance only (same value as calcSurfaceQuery().distance) [m].
    double calcSignedDistance(const SimTK::Vec3& p_B) const {
        return calcSurfaceQuery(p_B).distance;
    }
    /// Surface point furthest along the unit direction d_B (body frame) [m].
    SimTK::Vec3 calcSupportPoint(const SimTK::Vec3& d_B) const;
    /// Surface area [m^2] (ellipsoid: Knud Thomsen's approximation, within about 1 %).
    double calcSurfaceArea() const;
    /// Enclosed volume [m^3].
    double calcVolume() const;
    /// Covers the surface with patches of about spacing x spacing (point, outward normal,
    /// area); the areas sum to the surface area within about 1.5 % (tested). @pre spacing > 0.
    std::vector<SurfaceSample> calcSurfaceSamples(double spacing) const;

  private:
    ContactShape() = default;
    void updateBounds();

    Kind m_kind = Kind::Ellipsoid;
    SimTK::Vec3 m_semiAxes{0};
    SimTK::Transform m_X_BS;
    SimTK::Vec3 m_pA{0}, m_pB{0};
    double m_rA = 0, m_rB = 0;
    SimTK::Vec3 m_boundCentre{0};
    double m_boundRadius = 0;
};

}  // namespace body

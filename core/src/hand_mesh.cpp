// Procedural hand mesh. Every part is a closed surface made of vertex rings stitched into triangles:
//  - five tubes (thumb from its carpometacarpal joint, fingers from their knuckles) whose radius follows the
//    joint radii, with hemispherical caps (the rounded tips);
//  - a palm slab, a superellipsoid spanning wrist to knuckles.
// Each ring holds as many vertices as its circumference allows at the target spacing, so the vertex density is
// even over the skin: the paper samples particles uniformly among vertices, which is only uniform over the
// skin when the vertices are. Parts overlap (finger bases sink into the palm); vertices buried inside another
// part are marked unexposed so no particle lands there.
#include "hand_mesh.h"

#include "validate.h"

#include <algorithm>
#include <cmath>

namespace handsim {
namespace {

struct Influence {
  std::array<int, 4> bone{};
  std::array<double, 4> weight{};
};

Influence single(int bone) {
  Influence in;
  in.bone[0] = bone;
  in.weight[0] = 1;
  return in;
}

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

struct MeshBuilder {
  std::vector<Vec3> pos;
  std::vector<Influence> influence;
  std::vector<int> part;
  std::vector<int> tris;

  struct Ring {
    int first = 0;
    std::vector<double> param;  // position around the ring in [0, 1), increasing
  };

  // Joins consecutive rings a -> b (b further along the part's axis) with triangles facing outwards, walking
  // both rings by their parameters; a single-vertex ring (a pole) yields a fan.
  void stitch(const Ring& a, const Ring& b) {
    const int na = int(a.param.size()), nb = int(b.param.size());
    auto pa = [&](int i) { return i < na ? a.param[i] : 1.0 + a.param[0]; };
    auto pb = [&](int j) { return j < nb ? b.param[j] : 1.0 + b.param[0]; };
    int i = 0, j = 0;
    while (i < na || j < nb) {
      int ai = a.first + i % na, bj = b.first + j % nb;
      if (j >= nb || (i < na && pa(i + 1) < pb(j + 1))) {
        add_tri(ai, a.first + (i + 1) % na, bj);
        ++i;
      } else {
        add_tri(ai, b.first + (j + 1) % nb, bj);
        ++j;
      }
    }
  }
  void add_tri(int x, int y, int z) {
    if (x == y || y == z || x == z) return;  // degenerate at poles
    tris.insert(tris.end(), {x, y, z});
  }
  Ring add_ring(const std::vector<Vec3>& pts, const std::vector<double>& param, const Influence& in, int p) {
    Ring r{int(pos.size()), param};
    for (const Vec3& v : pts) {
      pos.push_back(v);
      influence.push_back(in);
      part.push_back(p);
    }
    return r;
  }
  // Flips the triangles of a part if its signed volume is negative, so every part faces outwards.
  void orient_part(size_t tri_begin) {
    double vol = 0;
    for (size_t t = tri_begin; t < tris.size(); t += 3)
      vol += pos[tris[t]].dot(pos[tris[t + 1]].cross(pos[tris[t + 2]]));
    if (vol < 0)
      for (size_t t = tri_begin; t < tris.size(); t += 3) std::swap(tris[t + 1], tris[t + 2]);
  }
};

// ---- Tubes -------------------------------------------------------------------------------------------------

struct Tube {
  std::vector<Vec3> p;      // joint positions along the chain
  std::vector<double> r;    // joint radii
  std::vector<double> S;    // arc length at each joint
  std::vector<int> bones;   // bone sequence: [base bone,] one per segment
  std::vector<double> breaks, half_width;  // where the bone changes, and the blend half-width there
  Vec3 x0;                  // ring basis start (the first joint's X axis)

  double length() const { return S.back(); }
  int segment(double s) const {
    int k = 0;
    while (k + 2 < int(S.size()) && s > S[k + 1]) ++k;
    return k;
  }
  Vec3 dir(int k) const { return (p[k + 1] - p[k]).normalized(); }
  Vec3 centre(double s) const {
    if (s <= 0) return p.front() + s * dir(0);
    if (s >= length()) return p.back() + (s - length()) * dir(int(p.size()) - 2);
    int k = segment(s);
    double t = (s - S[k]) / (S[k + 1] - S[k]);
    return (1 - t) * p[k] + t * p[k + 1];
  }
  double radius(double s) const {
    if (s <= 0) return r.front();
    if (s >= length()) return r.back();
    int k = segment(s);
    double t = (s - S[k]) / (S[k + 1] - S[k]);
    return (1 - t) * r[k] + t * r[k + 1];
  }
  // Segment directions blended over half a radius around each inner joint, so rings do not fold at kinks.
  Vec3 tangent(double s) const {
    int k = segment(std::clamp(s, 0.0, length()));
    Vec3 t = dir(k);
    for (int j = 1; j + 1 < int(p.size()); ++j) {
      double hw = 0.5 * r[j];
      if (std::abs(s - S[j]) < hw) {
        double b = smoothstep((s - S[j] + hw) / (2 * hw));
        t = ((1 - b) * dir(j - 1) + b * dir(j)).normalized();
      }
    }
    return t;
  }
  // Rigid along each bone, a smoothstep blend of the two bones across each joint.
  Influence weights(double s) const {
    for (size_t q = 0; q < breaks.size(); ++q) {
      if (s < breaks[q] - half_width[q]) return single(bones[q]);
      if (s < breaks[q] + half_width[q]) {
        double b = smoothstep((s - breaks[q] + half_width[q]) / (2 * half_width[q]));
        Influence in;
        in.bone = {bones[q], bones[q + 1], 0, 0};
        in.weight = {1 - b, b, 0, 0};
        return in;
      }
    }
    return single(bones.back());
  }
  // Signed distance to the tube surface (negative inside), approximating the radius along the closest point.
  double signed_distance(const Vec3& x) const {
    double best = 1e300;
    for (size_t k = 0; k + 1 < p.size(); ++k) {
      Vec3 d = p[k + 1] - p[k];
      double t = std::clamp((x - p[k]).dot(d) / d.squaredNorm(), 0.0, 1.0);
      double rr = (1 - t) * r[k] + t * r[k + 1];
      best = std::min(best, (x - (p[k] + t * d)).norm() - rr);
    }
    return best;
  }
};

Tube make_tube(const HandFrame& bind, const std::vector<int>& joints, int base_bone) {
  Tube t;
  double s = 0;
  for (size_t i = 0; i < joints.size(); ++i) {
    const JointPose& j = bind.joints[joints[i]];
    if (i > 0) s += (j.position - t.p.back()).norm();
    t.p.push_back(j.position);
    t.r.push_back(j.radius);
    t.S.push_back(s);
  }
  if (base_bone >= 0) {
    t.bones.push_back(base_bone);
    t.breaks.push_back(0.0);
    t.half_width.push_back(0.6 * t.r[0]);
  }
  for (size_t i = 0; i + 1 < joints.size(); ++i) {
    t.bones.push_back(joints[i]);  // the tip joint carries no bone: its segment ends there
    if (i > 0) {
      t.breaks.push_back(t.S[i]);
      t.half_width.push_back(0.6 * t.r[i]);
    }
  }
  t.x0 = bind.joints[joints[0]].orientation * Vec3::UnitX();
  return t;
}

int ring_count(double circumference, double h) {
  return circumference < 1e-12 ? 1 : std::max(3, int(std::lround(circumference / h)));
}

void build_tube(const Tube& t, double h, int part, MeshBuilder& mb) {
  struct Station {
    double s;     // arc length, negative / beyond the end on the caps
    double rho;   // ring radius
  };
  std::vector<Station> st;
  const double r0 = t.r.front(), r1 = t.r.back(), L = t.length();
  int nc0 = std::max(2, int(std::ceil(0.5 * M_PI * r0 / h)));
  for (int i = 0; i <= nc0; ++i) {
    double phi = 0.5 * M_PI * i / nc0;
    st.push_back({-r0 * std::cos(phi), r0 * std::sin(phi)});
  }
  int nb = std::max(1, int(std::ceil(L / h)));
  for (int i = 1; i < nb; ++i) st.push_back({L * i / nb, t.radius(L * i / nb)});
  int nc1 = std::max(2, int(std::ceil(0.5 * M_PI * r1 / h)));
  for (int i = nc1; i >= 0; --i) {
    double phi = 0.5 * M_PI * i / nc1;
    st.push_back({L + r1 * std::cos(phi), r1 * std::sin(phi)});
  }
  st.front().rho = st.back().rho = 0;  // exact poles

  size_t tri_begin = mb.tris.size();
  Vec3 x = t.x0;
  MeshBuilder::Ring prev;
  for (size_t i = 0; i < st.size(); ++i) {
    Vec3 tan = t.tangent(st[i].s);
    x = (x - x.dot(tan) * tan).normalized();  // parallel transport keeps rings aligned
    Vec3 y = tan.cross(x);
    Vec3 c = t.centre(st[i].s);
    int n = ring_count(2 * M_PI * st[i].rho, h);
    std::vector<Vec3> pts(n);
    std::vector<double> param(n);
    for (int j = 0; j < n; ++j) {
      double th = 2 * M_PI * j / n;
      pts[j] = c + st[i].rho * (std::cos(th) * x + std::sin(th) * y);
      param[j] = double(j) / n;
    }
    MeshBuilder::Ring ring = mb.add_ring(pts, param, t.weights(st[i].s), part);
    if (i > 0) mb.stitch(prev, ring);
    prev = ring;
  }
  mb.orient_part(tri_begin);
}

// ---- Palm --------------------------------------------------------------------------------------------------

struct Palm {
  Vec3 c;           // centre
  Vec3 half;        // a (x), b (y, thickness), c (z)
  double e1 = 0.45, e2 = 0.55;  // superellipsoid exponents: vertical profile, outline

  static double C(double w, double e) { return std::copysign(std::pow(std::abs(std::cos(w)), e), std::cos(w)); }
  static double S(double w, double e) { return std::copysign(std::pow(std::abs(std::sin(w)), e), std::sin(w)); }
  // v in [-pi/2, pi/2] from the palm side (-Y) to the back (+Y), u around.
  Vec3 point(double v, double u) const {
    return c + Vec3(half.x() * C(v, e1) * C(u, e2), half.y() * S(v, e1), half.z() * C(v, e1) * S(u, e2));
  }
  double inside_value(const Vec3& p, double margin) const {
    Vec3 q = p - c;
    double ax = std::abs(q.x()) / (half.x() - margin), ay = std::abs(q.y()) / (half.y() - margin),
           az = std::abs(q.z()) / (half.z() - margin);
    return std::pow(std::pow(ax, 2 / e2) + std::pow(az, 2 / e2), e2 / e1) + std::pow(ay, 2 / e1);
  }
};

// Parameters at equal arc length along a sampled curve (table of cumulative lengths over params).
std::vector<double> equal_arc_params(const std::vector<double>& par, const std::vector<double>& cum, int n,
                                     bool include_end) {
  std::vector<double> out;
  int count = include_end ? n + 1 : n;
  size_t k = 0;
  for (int i = 0; i < count; ++i) {
    double want = cum.back() * i / n;
    while (k + 2 < cum.size() && cum[k + 1] < want) ++k;
    double span = cum[k + 1] - cum[k];
    double t = span > 0 ? std::clamp((want - cum[k]) / span, 0.0, 1.0) : 0.0;
    out.push_back(par[k] + t * (par[k + 1] - par[k]));
  }
  return out;
}

void build_palm(const Palm& palm, double h, const std::vector<std::pair<Vec3, Vec3>>& bone_segments,
                const std::vector<int>& bone_ids, int part, MeshBuilder& mb) {
  constexpr int kFine = 512;
  // Meridian spacing: average of the meridians through the long and the short axis.
  std::vector<double> vpar(kFine + 1), vcum(kFine + 1, 0.0);
  for (int i = 0; i <= kFine; ++i) {
    vpar[i] = -0.5 * M_PI + M_PI * i / kFine;
    if (i > 0) {
      double d0 = (palm.point(vpar[i], 0) - palm.point(vpar[i - 1], 0)).norm();
      double d1 = (palm.point(vpar[i], 0.5 * M_PI) - palm.point(vpar[i - 1], 0.5 * M_PI)).norm();
      vcum[i] = vcum[i - 1] + 0.5 * (d0 + d1);
    }
  }
  int nv = std::max(2, int(std::lround(vcum.back() / h)));
  std::vector<double> vs = equal_arc_params(vpar, vcum, nv, true);

  size_t tri_begin = mb.tris.size();
  MeshBuilder::Ring prev;
  for (int i = 0; i <= nv; ++i) {
    std::vector<Vec3> pts;
    std::vector<double> param;
    if (i == 0 || i == nv) {
      pts.push_back(palm.point(vs[i], 0));
      param.push_back(0);
    } else {
      std::vector<double> upar(kFine + 1), ucum(kFine + 1, 0.0);
      for (int k = 0; k <= kFine; ++k) {
        upar[k] = 2 * M_PI * k / kFine;
        if (k > 0) ucum[k] = ucum[k - 1] + (palm.point(vs[i], upar[k]) - palm.point(vs[i], upar[k - 1])).norm();
      }
      int nu = ring_count(ucum.back(), h);
      for (double u : equal_arc_params(upar, ucum, nu, false)) {
        pts.push_back(palm.point(vs[i], u));
        param.push_back(u / (2 * M_PI));
      }
    }
    // Influences per vertex: inverse-distance weights to the palm's bones, the 4 strongest kept.
    MeshBuilder::Ring ring{int(mb.pos.size()), param};
    for (const Vec3& v : pts) {
      std::vector<std::pair<double, int>> w;
      for (size_t b = 0; b < bone_segments.size(); ++b) {
        const Vec3 &a = bone_segments[b].first, &e = bone_segments[b].second;
        Vec3 d = e - a;
        double t = d.squaredNorm() > 0 ? std::clamp((v - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
        double dist2 = (v - (a + t * d)).squaredNorm();
        const double eps2 = 0.005 * 0.005;
        w.push_back({1.0 / ((dist2 + eps2) * (dist2 + eps2)), bone_ids[b]});
      }
      std::sort(w.begin(), w.end(), [](auto& x, auto& y) { return x.first > y.first; });
      Influence in;
      double sum = 0;
      for (int k = 0; k < 4; ++k) sum += w[k].first;
      for (int k = 0; k < 4; ++k) {
        in.bone[k] = w[k].second;
        in.weight[k] = w[k].first / sum;
      }
      mb.pos.push_back(v);
      mb.influence.push_back(in);
      mb.part.push_back(part);
    }
    if (i > 0) mb.stitch(prev, ring);
    prev = ring;
  }
  mb.orient_part(tri_begin);
}

double tube_area(const Tube& t) {
  double a = 2 * M_PI * (t.r.front() * t.r.front() + t.r.back() * t.r.back());
  for (size_t k = 0; k + 1 < t.p.size(); ++k) a += M_PI * (t.r[k] + t.r[k + 1]) * (t.S[k + 1] - t.S[k]);
  return a;
}

}  // namespace

ProceduralHandMesh build_procedural_hand_mesh(const HandFrame& bind, int target_vertices) {
  std::vector<Tube> tubes;
  tubes.push_back(make_tube(bind, {kThumbMetacarpal, kThumbProximal, kThumbDistal, kThumbTip}, kWrist));
  for (int f = 0; f < 4; ++f) {
    int m = kIndexMetacarpal + 5 * f;
    tubes.push_back(make_tube(bind, {m + 1, m + 2, m + 3, m + 4}, m));
  }

  // The palm spans the knuckles sideways and wrist to knuckles lengthwise.
  const auto& J = bind.joints;
  double x0 = std::min(J[kIndexProximal].position.x(), J[kLittleProximal].position.x());
  double x1 = std::max(J[kIndexProximal].position.x(), J[kLittleProximal].position.x());
  double z_front = J[kMiddleProximal].position.z() - 0.3 * J[kMiddleProximal].radius;
  double z_back = J[kWrist].position.z() + 0.5 * J[kWrist].radius;
  Palm palm;
  double rk = 0.5 * (J[kIndexProximal].radius + J[kLittleProximal].radius);
  palm.c = Vec3(0.5 * (x0 + x1), J[kPalm].position.y(), 0.5 * (z_front + z_back));
  palm.half = Vec3(0.5 * (x1 - x0) + rk, J[kPalm].radius, 0.5 * (z_back - z_front));

  // Spacing h from the total area so the vertex count lands near the target.
  double area = 0;
  for (const Tube& t : tubes) area += tube_area(t);
  const Vec3& ph = palm.half;
  area += 8 * ph.x() * ph.z() * 0.93 + 2 * ph.y() * 4 * (ph.x() + ph.z()) * 0.95;
  double h = std::sqrt(area / std::max(target_vertices, 200));

  std::vector<std::pair<Vec3, Vec3>> segs = {{J[kWrist].position, J[kWrist].position},
                                             {J[kThumbMetacarpal].position, J[kThumbProximal].position}};
  std::vector<int> ids = {kWrist, kThumbMetacarpal};
  for (int f = 0; f < 4; ++f) {
    int m = kIndexMetacarpal + 5 * f;
    segs.push_back({J[m].position, J[m + 1].position});
    ids.push_back(m);
  }
  const int palm_part = int(tubes.size());
  auto build = [&](double spacing) {
    MeshBuilder mb;
    for (size_t i = 0; i < tubes.size(); ++i) build_tube(tubes[i], spacing, int(i), mb);
    build_palm(palm, spacing, segs, ids, palm_part, mb);
    return mb;
  };
  // The area estimate is rough (rings round their counts); one correction pass lands within ~1%.
  MeshBuilder mb = build(h);
  h *= std::sqrt(double(mb.pos.size()) / std::max(target_vertices, 200));
  mb = build(h);

  ProceduralHandMesh out;
  const int n = int(mb.pos.size());
  out.mesh.positions.resize(3, n);
  out.mesh.bones.resize(4, n);
  out.mesh.weights.resize(4, n);
  out.exposed.assign(n, 1);
  const double margin = 0.2 * h;  // a vertex on the rim where two parts meet still counts as skin
  for (int i = 0; i < n; ++i) {
    out.mesh.positions.col(i) = mb.pos[i];
    for (int k = 0; k < 4; ++k) {
      out.mesh.bones(k, i) = mb.influence[i].bone[k];
      out.mesh.weights(k, i) = mb.influence[i].weight[k];
    }
    for (size_t t = 0; t < tubes.size() && out.exposed[i]; ++t)
      if (int(t) != mb.part[i] && tubes[t].signed_distance(mb.pos[i]) < -margin) out.exposed[i] = 0;
    if (mb.part[i] != palm_part && palm.inside_value(mb.pos[i], margin) < 1) out.exposed[i] = 0;
  }
  out.mesh.triangles = std::move(mb.tris);
  return out;
}

SkinnedMesh make_hand_mesh(const HandFrame& bind, int target_vertices) {
  validate_frame(bind, "bind");
  if (target_vertices < 200) validate::fail("target_vertices", "must be >= 200, got " + std::to_string(target_vertices));
  for (const JointPose& j : bind.joints)
    if (!j.valid) validate::fail("bind", "every joint of a bind frame must be valid");
  return build_procedural_hand_mesh(bind, target_vertices).mesh;
}

}  // namespace handsim

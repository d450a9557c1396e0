/* test_collider_motion.c - moving colliders and the boundary rule (src/collide; Gao et al.
 * 2017 sec. 3.2 step 4).
 *
 * Truth is computed here, independently of the library and in double: moving poses from a
 * Rodrigues rotation written here, collider velocities as finite differences of a material
 * point's trajectory, and the boundary rule from its definition. The level sets of still
 * colliders are tested in test_collider.c. */
#include "support.h"
#include "collider_support.h"
#include "collide/boundary.h"
#include "collide/collider.h"

#include <math.h>
#include <string.h>

/* ---- motion -----------------------------------------------------------------------------------
 */

/* A translated and rotated collider at time t has the static shape's phi at the inversely
 * transformed point, and its normal is the static normal rotated. */
static void test_moving_phi(void **state) {
  (void)state;
  uint64_t rng = 99;
  const double tol = TOL(2e-5, 1e-12);
  const double times[3] = {0.0, 1.7, -2.3};
  for (int s = 0; s < SHAPES; ++s) {
    const mpm_collider_desc d0 = shape_desc(s), d = moving(d0);
    mpm_collider c0, c;
    assert_int_equal(mpm_collider_init(&c0, &d0), MPM_OK);
    assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
    const mpm_collider_pose still = mpm_collider_pose_at(&c0, 5.0); /* no motion: any time */
    for (int ti = 0; ti < 3; ++ti) {
      const double t = times[ti];
      const mpm_collider_pose pose = mpm_collider_pose_at(&c, t);
      double R[9], ctr[3];
      rot(d.motion.axis, d.motion.angular_speed * t, R);
      for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + d.motion.velocity[j] * t;
      for (int trial = 0; trial < 500; ++trial) {
        double x[3], r[3], xs[3], p[3], n[3], ns[3], margin;
        for (int j = 0; j < 3; ++j) x[j] = ctr[j] + test_rand(&rng, -2.5, 2.5);
        for (int j = 0; j < 3; ++j) r[j] = x[j] - ctr[j];
        for (int j = 0; j < 3; ++j) {
          p[j] = R[j] * r[0] + R[3 + j] * r[1] + R[6 + j] * r[2]; /* R^T r */
          xs[j] = d.shape.center[j] + p[j];
        }
        const double phi = phi_at(&pose, x, n), phis = phi_at(&still, xs, ns);
        assert_close(phi, phis, tol);
        ref_phi(&d.shape, p, &margin);
        if (margin < 1e-3) continue; /* the normal may pick another tied face */
        for (int j = 0; j < 3; ++j)
          assert_close(n[j], R[3 * j] * ns[0] + R[3 * j + 1] * ns[1] + R[3 * j + 2] * ns[2], tol);
      }
    }
    mpm_collider_free(&c0);
    mpm_collider_free(&c);
  }
}

/* Pose at t against the definition: centre + v t and the Rodrigues rotation. */
static void check_pose(const mpm_collider_pose *pose, const double ctr[3], const double R[9],
                       const double v[3], const double w[3]) {
  const double tol = TOL(2e-6, 1e-13);
  for (int j = 0; j < 3; ++j) {
    assert_close(pose->center[j], ctr[j], tol * 4);
    assert_close(pose->velocity[j], v[j], tol);
    assert_close(pose->omega[j], w[j], tol);
  }
  for (int j = 0; j < 9; ++j) assert_close(pose->R[j], R[j], tol);
}

/* x(t) of the material point with local coordinates q: centre(t) + R(t) q, from the poses. */
static void trajectory(const mpm_collider *c, double t, const double q[3], double x[3]) {
  const mpm_collider_pose p = mpm_collider_pose_at(c, t);
  for (int i = 0; i < 3; ++i)
    x[i] = p.center[i] + p.R[3 * i] * q[0] + p.R[3 * i + 1] * q[1] + p.R[3 * i + 2] * q[2];
}

/* The collider velocity at a material point equals (x(t+h) - x(t-h)) / 2h. */
static void check_velocity_fd(const mpm_collider *c, double t, uint64_t *rng) {
  const double h = TOL(1e-2, 1e-5), tol = TOL(2e-3, 1e-7);
  const mpm_collider_pose pose = mpm_collider_pose_at(c, t);
  for (int trial = 0; trial < 50; ++trial) {
    double q[3], x[3], xp[3], xm[3];
    for (int j = 0; j < 3; ++j) q[j] = test_rand(rng, -1.5, 1.5);
    trajectory(c, t, q, x);
    trajectory(c, t + h, q, xp);
    trajectory(c, t - h, q, xm);
    const mpm_real xr[3] = {(mpm_real)x[0], (mpm_real)x[1], (mpm_real)x[2]};
    mpm_real v[3];
    mpm_collider_velocity(&pose, xr, v);
    for (int j = 0; j < 3; ++j) assert_close(v[j], (xp[j] - xm[j]) / (2 * h), tol);
  }
}

static void test_constant_motion(void **state) {
  (void)state;
  uint64_t rng = 5;
  const mpm_collider_desc d = moving(shape_desc(0));
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
  const double times[5] = {0.0, 0.35, 1.9, 4.0, 40.0}; /* 36 rad: several turns */
  for (int ti = 0; ti < 5; ++ti) {
    const double t = times[ti];
    double R[9], ctr[3], w[3];
    rot(d.motion.axis, d.motion.angular_speed * t, R);
    for (int j = 0; j < 3; ++j) {
      ctr[j] = d.shape.center[j] + d.motion.velocity[j] * t;
      w[j] = d.motion.axis[j] * d.motion.angular_speed;
    }
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, t);
    check_pose(&pose, ctr, R, d.motion.velocity, w);
    check_velocity_fd(&c, t, &rng);
  }
  mpm_collider_free(&c);

  /* pure translation with no rotation axis at all */
  mpm_collider_desc dt = shape_desc(1);
  set3(dt.motion.velocity, -1.0, 0.5, 2.0);
  assert_int_equal(mpm_collider_init(&c, &dt), MPM_OK);
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zero[3] = {0, 0, 0};
  double ctr[3];
  for (int j = 0; j < 3; ++j) ctr[j] = dt.shape.center[j] + dt.motion.velocity[j] * 1.5;
  const mpm_collider_pose pose = mpm_collider_pose_at(&c, 1.5);
  check_pose(&pose, ctr, I, dt.motion.velocity, zero);
  check_velocity_fd(&c, 1.5, &rng);
  mpm_collider_free(&c);
}

static void test_keyframes(void **state) {
  (void)state;
  uint64_t rng = 6;
  mpm_keyframe k[3];
  memset(k, 0, sizeof k);
  k[0].time = 0.5;
  set3(k[0].translation, 0.2, 0.0, -0.1);
  k[0].angle = 0.1;
  k[1].time = 1.5;
  set3(k[1].translation, 1.2, -2.0, 0.4);
  k[1].angle = 1.3;
  k[2].time = 2.0;
  set3(k[2].translation, 1.0, 0.0, 0.0);
  k[2].angle = -0.3;
  mpm_collider_desc d = shape_desc(2);
  set3(d.motion.axis, 0.0, 0.6, 0.8);
  set3(d.motion.velocity, 9, 9, 9); /* ignored when there are keyframes */
  d.motion.angular_speed = 9;
  d.motion.keyframe_count = 3;
  d.motion.keyframes = k;
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
  /* the collider owns a copy: changing the scene's array afterwards changes nothing */
  mpm_keyframe saved[3];
  memcpy(saved, k, sizeof k);
  memset(k, 0, sizeof k);
  assert_ptr_not_equal(c.desc.motion.keyframes, k);

  /* mid-segment: piecewise linear pose, slopes as velocities */
  const double mids[2] = {0.9, 1.8};
  for (int m = 0; m < 2; ++m) {
    const int i = m;
    const double t = mids[m], span = saved[i + 1].time - saved[i].time;
    const double u = (t - saved[i].time) / span;
    double R[9], ctr[3], v[3], w[3];
    const double angle = saved[i].angle + u * (saved[i + 1].angle - saved[i].angle);
    rot(d.motion.axis, angle, R);
    for (int j = 0; j < 3; ++j) {
      const double dtr = saved[i + 1].translation[j] - saved[i].translation[j];
      ctr[j] = d.shape.center[j] + saved[i].translation[j] + u * dtr;
      v[j] = dtr / span;
      w[j] = d.motion.axis[j] * (saved[i + 1].angle - saved[i].angle) / span;
    }
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, t);
    check_pose(&pose, ctr, R, v, w);
    check_velocity_fd(&c, t, &rng);
  }

  /* held outside the span, at rest */
  const double zero[3] = {0, 0, 0};
  const double outside[4] = {-3.0, 0.2, 2.0, 7.5};
  for (int m = 0; m < 4; ++m) {
    const mpm_keyframe *e = outside[m] < saved[0].time ? &saved[0] : &saved[2];
    double R[9], ctr[3];
    rot(d.motion.axis, e->angle, R);
    for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + e->translation[j];
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, outside[m]);
    check_pose(&pose, ctr, R, zero, zero);
  }
  /* at the first keyframe the pose is the keyframe's */
  {
    double R[9], ctr[3];
    rot(d.motion.axis, saved[0].angle, R);
    for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + saved[0].translation[j];
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, saved[0].time);
    const double tol = TOL(2e-6, 1e-13);
    for (int j = 0; j < 3; ++j) assert_close(pose.center[j], ctr[j], tol);
    for (int j = 0; j < 9; ++j) assert_close(pose.R[j], R[j], tol);
  }
  mpm_collider_free(&c);
  assert_null(c.desc.motion.keyframes);

  /* a single keyframe: a fixed offset at every time */
  d.motion.keyframes = saved + 1;
  d.motion.keyframe_count = 1;
  assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
  for (int m = 0; m < 3; ++m) {
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, -1.0 + 2.0 * m);
    double R[9], ctr[3];
    rot(d.motion.axis, saved[1].angle, R);
    for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + saved[1].translation[j];
    check_pose(&pose, ctr, R, zero, zero);
  }
  mpm_collider_free(&c);
}

/* A rotating collider moves the material with it: a node at the surface of a spinning sphere
 * gets omega x r from a sticky rule. */
static void test_collider_velocity_rotation(void **state) {
  (void)state;
  mpm_collider_desc d = make_desc(MPM_SHAPE_SPHERE);
  d.shape.radius = 1.0;
  set3(d.motion.axis, 0, 0, 1);
  d.motion.angular_speed = 2.0;
  set3(d.motion.velocity, 0.5, 0, 0);
  d.rule = MPM_BOUNDARY_STICKY;
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
  const mpm_collider_pose pose = mpm_collider_pose_at(&c, 2.0); /* centre (1, 0, 0) */
  const mpm_real x[3] = {1, R_(0.9), 0};
  mpm_real v[3] = {3, 4, 5};
  assert_int_equal(mpm_collider_apply(&pose, x, 0, v), 1);
  /* 0.5 x^ + 2 z^ x 0.9 y^ = (0.5 - 1.8, 0, 0) */
  assert_close(v[0], -1.3, TOL(1e-6, 1e-14));
  assert_close(v[1], 0.0, TOL(1e-6, 1e-14));
  assert_close(v[2], 0.0, TOL(1e-6, 1e-14));
  mpm_collider_free(&c);
}

/* ---- boundary rule
 * ------------------------------------------------------------------------------- */

static void project(mpm_boundary_rule rule, double mu, const double n[3], const double vo[3],
                    const double v[3], double out[3]) {
  const mpm_real nr[3] = {(mpm_real)n[0], (mpm_real)n[1], (mpm_real)n[2]};
  const mpm_real vor[3] = {(mpm_real)vo[0], (mpm_real)vo[1], (mpm_real)vo[2]};
  mpm_real vr[3] = {(mpm_real)v[0], (mpm_real)v[1], (mpm_real)v[2]};
  mpm_boundary_project(rule, (mpm_real)mu, nr, vor, vr);
  for (int d = 0; d < 3; ++d) out[d] = (double)vr[d];
}

/* Split v - vo into normal and tangential parts along n. */
static void split(const double n[3], const double vo[3], const double v[3], double *vn,
                  double vt[3]) {
  double r[3];
  for (int d = 0; d < 3; ++d) r[d] = v[d] - vo[d];
  *vn = dot3(r, n);
  for (int d = 0; d < 3; ++d) vt[d] = r[d] - *vn * n[d];
}

static void test_boundary_rules(void **state) {
  (void)state;
  uint64_t rng = 31;
  const double tol = TOL(2e-5, 1e-12);
  for (int trial = 0; trial < 500; ++trial) {
    double n[3], vo[3], v[3], out[3];
    for (int d = 0; d < 3; ++d) {
      n[d] = test_rand(&rng, -1, 1);
      vo[d] = test_rand(&rng, -2, 2);
      v[d] = test_rand(&rng, -3, 3);
    }
    unit3(n);
    double vn, vt[3];
    split(n, vo, v, &vn, vt);
    const double speed = sqrt(dot3(vt, vt));

    /* sticky: the obstacle's velocity, whatever the friction */
    project(MPM_BOUNDARY_STICKY, 0.7, n, vo, v, out);
    for (int d = 0; d < 3; ++d) assert_close(out[d], vo[d], tol);

    /* slip without friction: normal part removed, tangential kept */
    project(MPM_BOUNDARY_SLIP, 0.0, n, vo, v, out);
    double on, ot[3];
    split(n, vo, out, &on, ot);
    assert_close(on, 0.0, tol);
    for (int d = 0; d < 3; ++d) assert_close(ot[d], vt[d], tol);

    /* separate: a separating velocity is left exactly alone, an approaching one slips */
    project(MPM_BOUNDARY_SEPARATE, 0.5, n, vo, v, out);
    if (vn > 0) {
      for (int d = 0; d < 3; ++d) assert_close(out[d], v[d], TOL(1e-6, 1e-15) * 4);
    } else {
      split(n, vo, out, &on, ot);
      assert_close(on, 0.0, tol);
    }

    /* friction: tangential speed reduced by mu |vn| along the same direction, or stopped */
    const double mu = test_rand(&rng, 0.0, 1.5);
    const mpm_boundary_rule rules[2] = {MPM_BOUNDARY_SLIP, MPM_BOUNDARY_SEPARATE};
    for (int ri = 0; ri < 2; ++ri) {
      if (rules[ri] == MPM_BOUNDARY_SEPARATE && vn >= 0) continue;
      project(rules[ri], mu, n, vo, v, out);
      split(n, vo, out, &on, ot);
      assert_close(on, 0.0, tol);
      const double expect = fmax(0.0, speed - mu * fabs(vn));
      assert_close(sqrt(dot3(ot, ot)), expect, tol);
      if (expect > 0)
        for (int d = 0; d < 3; ++d) assert_close(ot[d] * speed, vt[d] * expect, tol * 4);
    }
  }
  /* by hand: floor normal +y, still obstacle, v = (3, -1, 0), mu = 0.5 -> (2.5, 0, 0) */
  const double n[3] = {0, 1, 0}, vo[3] = {0, 0, 0}, v[3] = {3, -1, 0};
  double out[3];
  project(MPM_BOUNDARY_SLIP, 0.5, n, vo, v, out);
  assert_close(out[0], 2.5, tol);
  assert_close(out[1], 0.0, tol);
  /* mu = 4: |vt| = 3 <= 4 -> stopped */
  project(MPM_BOUNDARY_SEPARATE, 4.0, n, vo, v, out);
  for (int d = 0; d < 3; ++d) assert_close(out[d], 0.0, tol);
  /* separating: no friction */
  const double up[3] = {3, 1, 0};
  project(MPM_BOUNDARY_SEPARATE, 4.0, n, vo, up, out);
  for (int d = 0; d < 3; ++d) assert_close(out[d], up[d], tol);
  /* moving obstacle: only the relative velocity is projected */
  const double belt[3] = {1, 0, 0}, w[3] = {1, -2, 0.5};
  project(MPM_BOUNDARY_SLIP, 0.0, n, belt, w, out);
  assert_close(out[0], 1.0, tol);
  assert_close(out[1], 0.0, tol);
  assert_close(out[2], 0.5, tol);
}

/* apply(): nodes outside are untouched; nodes inside get the rule with the collider's normal
 * and velocity at that node. */
static void test_apply(void **state) {
  (void)state;
  uint64_t rng = 8;
  for (int s = 0; s < SHAPES; ++s) {
    for (int io = 0; io < 2; ++io) {
      mpm_collider_desc d = moving(shape_desc(s));
      d.inside_out = io;
      d.rule = (mpm_boundary_rule)(s % 3);
      d.friction = 0.3;
      mpm_collider c;
      assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
      const mpm_collider_pose pose = mpm_collider_pose_at(&c, 0.6);
      int inside = 0, outside = 0;
      for (int trial = 0; trial < 600; ++trial) {
        mpm_real x[3], v[3], v0[3], n[3], vo[3];
        for (int j = 0; j < 3; ++j) {
          x[j] = pose.center[j] + (mpm_real)test_rand(&rng, -1.6, 1.6);
          v[j] = v0[j] = (mpm_real)test_rand(&rng, -3, 3);
        }
        const mpm_real phi = mpm_collider_phi(&pose, x, n);
        const int changed = mpm_collider_apply(&pose, x, 0, v);
        if (phi > 0) {
          ++outside;
          assert_int_equal(changed, 0);
          assert_memory_equal(v, v0, sizeof v);
        } else {
          ++inside;
          assert_int_equal(changed, 1);
          mpm_collider_velocity(&pose, x, vo);
          mpm_boundary_project(d.rule, (mpm_real)d.friction, n, vo, v0);
          for (int j = 0; j < 3; ++j) assert_close(v[j], v0[j], TOL(1e-6, 1e-14));
        }
      }
      assert_true(inside > 20 && outside > 20);
      mpm_collider_free(&c);
    }
  }
}

/* A domain corner meets a slip obstacle as a separating one (mpm_boundary_rule_for,
 * collider.h): inside a slip half-space or beyond a slip wall, a grid node loses its normal
 * velocity whichever way it moves, a corner keeps it when it leaves (a corner projected onto a
 * wall must be free to come off it), and the implicit constraints agree. Sticky and separating
 * obstacles treat both alike. */
static void test_corner_leaves_slip(void **state) {
  (void)state;
  for (int r = 0; r < 3; ++r) {
    const mpm_boundary_rule rule = (mpm_boundary_rule)r;
    mpm_collider_desc d = make_desc(MPM_SHAPE_HALFSPACE);
    set3(d.shape.center, 0, 1, 0);
    set3(d.shape.axis, 0, 1, 0); /* the floor y < 1 */
    d.rule = rule;
    mpm_collider c;
    assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, 0);
    /* the floor alone, then the wall y > 2 alone */
    const mpm_boundary floor = {{-9, -9, -9}, {9, 9, 9}, MPM_BOUNDARY_SLIP, 0, 1, &pose};
    const mpm_boundary wall = {{-9, -9, -9}, {9, 2, 9}, rule, 0, 0, NULL};
    const mpm_real in_floor[3] = {0, R_(0.999), 0}, in_wall[3] = {0, R_(2.001), 0};
    for (int b = 0; b < 2; ++b) {
      const mpm_boundary *bd = b ? &wall : &floor;
      const mpm_real *x = b ? in_wall : in_floor;
      const mpm_real out = b ? -1 : 1; /* the normal velocity that leaves the obstacle */
      for (int corner = 0; corner < 2; ++corner)
        for (int leaving = 0; leaving < 2; ++leaving) {
          const mpm_real vy = leaving ? out : -out;
          mpm_real v[3] = {R_(0.5), vy, 0}, n[4][3], vo[4][3];
          mpm_boundary_apply(bd, x, 0, corner, v);
          const mpm_real vp[3] = {R_(0.5), vy, 0}; /* frictionless: vm does not matter */
          const int count = mpm_boundary_constraints(bd, x, 0, corner, vp, vp, n, vo);
          if (rule == MPM_BOUNDARY_STICKY) {
            assert_true(v[0] == 0 && v[1] == 0 && count == -1);
            continue;
          }
          /* kept: leaving a separating obstacle, or a slip one as a corner */
          const int kept = leaving && (rule == MPM_BOUNDARY_SEPARATE || corner);
          assert_true(v[0] == R_(0.5));
          assert_true(v[1] == (kept ? vy : 0));
          assert_int_equal(count, kept ? 0 : 1);
        }
    }
    mpm_collider_free(&c);
  }
}

/* Friction in the implicit solve's constraints (boundary.h): where a floor with friction 0.5
 * stops the motion vm (v^n + dt g), the DOF is held (-2) at what Coulomb's rule makes of vm, the
 * same velocity mpm_boundary_apply gives vm: stopped where static friction holds (a tangential
 * 0.3 against 0.5 x 1), slowed by 0.5 x 1 where it slides (2 -> 1.5); not from v (v* with the
 * elastic forces' explicit step, 40 m/s here); leaving the floor, no friction; frictionless,
 * the normal constraint alone (count 1). */
static void test_friction_constraints(void **state) {
  (void)state;
  mpm_collider_desc d = make_desc(MPM_SHAPE_HALFSPACE);
  set3(d.shape.center, 0, 1, 0);
  set3(d.shape.axis, 0, 1, 0); /* the floor y < 1 */
  d.rule = MPM_BOUNDARY_SEPARATE;
  d.friction = 0.5;
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
  const mpm_collider_pose pose = mpm_collider_pose_at(&c, 0);
  const mpm_boundary floor = {{-9, -9, -9}, {9, 9, 9}, MPM_BOUNDARY_SLIP, 0, 1, &pose};
  const mpm_real x[3] = {0, R_(0.999), 0}, v[3] = {40, -40, 0};
  const mpm_real tangential[3] = {R_(0.3), 2, 0};
  for (int k = 0; k < 3; ++k) {
    const mpm_real vm[3] = {tangential[k], k == 2 ? 1 : -1, 0};
    mpm_real n[4][3], vo[4][3], ref[3] = {vm[0], vm[1], vm[2]};
    const int count = mpm_boundary_constraints(&floor, x, 0, 0, v, vm, n, vo);
    mpm_boundary_apply(&floor, x, 0, 0, ref);
    if (k == 2) { /* leaving: no friction, and v* moving in: the normal constraint */
      assert_int_equal(count, 1);
      continue;
    }
    assert_int_equal(count, -2);
    for (int e = 0; e < 3; ++e) assert_true(fabs((double)(vo[0][e] - ref[e])) < 1e-6);
    assert_true(fabs((double)vo[0][0] - (k ? 1.5 : 0)) < 1e-6 && vo[0][1] == 0);
  }
  d.friction = 0;
  mpm_collider c0;
  assert_int_equal(mpm_collider_init(&c0, &d), MPM_OK);
  const mpm_collider_pose pose0 = mpm_collider_pose_at(&c0, 0);
  const mpm_boundary frictionless = {{-9, -9, -9}, {9, 9, 9}, MPM_BOUNDARY_SLIP, 0, 1, &pose0};
  mpm_real n[4][3], vo[4][3];
  const mpm_real vm[3] = {R_(0.3), -1, 0};
  assert_int_equal(mpm_boundary_constraints(&frictionless, x, 0, 0, v, vm, n, vo), 1);
  mpm_collider_free(&c);
  mpm_collider_free(&c0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_friction_constraints),
      cmocka_unit_test(test_moving_phi),
      cmocka_unit_test(test_constant_motion),
      cmocka_unit_test(test_keyframes),
      cmocka_unit_test(test_collider_velocity_rotation),
      cmocka_unit_test(test_boundary_rules),
      cmocka_unit_test(test_apply),
      cmocka_unit_test(test_corner_leaves_slip),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

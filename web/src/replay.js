// The 3D replay of a mission: the site, the stack as built, the base footprint and the arm (the
// URDF chain's links as simple shapes, posed from the recorded joint angles) and each sweep's
// cloud as it was taken. A time slider replays the mission; the camera orbits (OrbitControls).
import * as THREE from 'three';
import { createViewer, boxMesh, mat4 } from './viewer.js';

// Pose of a thing at (x, y, theta) on the floor.
function planar(x, y, theta) {
  return new THREE.Matrix4().makeRotationZ(theta).setPosition(x, y, 0);
}

// Link frames of the arm in the site at joint angles q (KDL segments: the joint turns about its
// axis through its origin, then the segment's tip frame follows).
export function armFrames(arm, T_site_base, q) {
  const frames = [];
  let T = T_site_base.clone().multiply(mat4(arm.T_base_arm_base));
  frames.push(T.clone());
  let j = 0;
  for (const s of arm.segments) {
    if (s.moves) {
      const o = new THREE.Vector3(...s.origin);
      const axis = new THREE.Vector3(...s.axis).normalize();
      const R = new THREE.Matrix4().makeRotationAxis(axis, q[j++] || 0);
      T = T.clone()
        .multiply(new THREE.Matrix4().makeTranslation(o.x, o.y, o.z))
        .multiply(R)
        .multiply(new THREE.Matrix4().makeTranslation(-o.x, -o.y, -o.z));
    }
    T = T.clone().multiply(mat4(s.tip));
    frames.push(T.clone());
  }
  return frames;
}

export function createReplay(container, slider, label, data) {
  const { scene: sc, replay, sweeps, bricks, visits, clouds } = data;
  const view = createViewer(container, { position: [3.2, -4.2, 3.4], target: [-0.3, 0.3, 0.4] });
  const { scene } = view;

  // The site: floor inside the boundary, walls and obstacles.
  const site = sc.site;
  if (site.boundary && site.boundary.length >= 3) {
    const shape = new THREE.Shape(site.boundary.map((p) => new THREE.Vector2(p[0], p[1])));
    const floor = new THREE.Mesh(new THREE.ShapeGeometry(shape),
      new THREE.MeshLambertMaterial({ color: 0xd6d2c8, side: THREE.DoubleSide }));
    floor.position.z = site.ground_z - 0.001;
    scene.add(floor);
  }
  const grid = new THREE.GridHelper(12, 24, 0x9aa3ad, 0xc3c9d0);
  grid.rotation.x = Math.PI / 2;
  grid.position.z = site.ground_z;
  scene.add(grid);
  for (const b of [...site.walls, ...site.obstacles]) {
    const wall = site.walls.includes(b);
    const m = boxMesh(b.size, wall ? 0xa9b1ba : 0x7b8fa3, wall ? 0.18 : 0.8);
    m.applyMatrix4(mat4(b.pose));
    scene.add(m);
  }
  for (const p of sc.positions || []) {
    const marker = new THREE.Mesh(new THREE.ConeGeometry(0.06, 0.2, 12), new THREE.MeshLambertMaterial({ color: 0x2457a6 }));
    marker.rotation.z = p.theta - Math.PI / 2;
    marker.position.set(p.x, p.y, 0.02);
    marker.rotateX(Math.PI / 2);
    scene.add(marker);
  }

  // The stack as built (true poses from brick_errors.csv), shown once each is placed.
  const brickSize = site.brick;
  const brickMeshes = [];
  for (let k = 0; k < bricks.rows; k++) {
    const m = boxMesh(brickSize, 0xb5502b);
    m.applyMatrix4(new THREE.Matrix4().makeRotationZ((bricks.col.yaw_deg[k] * Math.PI) / 180)
      .setPosition(bricks.col.x_m[k], bricks.col.y_m[k], bricks.col.z_m[k]));
    m.visible = false;
    scene.add(m);
    brickMeshes.push(m);
  }

  // The robot: base footprint and tracks, the arm's links, a brick in the gripper.
  const robot = new THREE.Group();
  robot.name = 'robot';
  const fp = sc.footprint;
  const T_base_arm = mat4(sc.arm.T_base_arm_base);
  const baseTop = Math.max(0.25, new THREE.Vector3().setFromMatrixPosition(T_base_arm).z);
  const body = boxMesh([fp.length, fp.width * 0.7, baseTop * 0.7], 0xe0a526);
  body.position.set(fp.offset[0], fp.offset[1], baseTop * 0.65);
  robot.add(body);
  for (const side of [-1, 1]) {
    const track = boxMesh([fp.length, fp.width * 0.15, baseTop * 0.6], 0x30343a);
    track.position.set(fp.offset[0], fp.offset[1] + side * (fp.width * 0.5 - fp.width * 0.075), baseTop * 0.3);
    robot.add(track);
  }
  const outline = new THREE.LineLoop(new THREE.BufferGeometry().setFromPoints([
    [-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]].map(([a, b]) =>
    new THREE.Vector3(fp.offset[0] + a * fp.length, fp.offset[1] + b * fp.width, 0.005))),
  new THREE.LineBasicMaterial({ color: 0x1d2a3a }));
  robot.add(outline);
  scene.add(robot);
  const linkMat = new THREE.MeshLambertMaterial({ color: 0xf08a24 });
  const jointMat = new THREE.MeshLambertMaterial({ color: 0x50555c });
  const nLinks = sc.arm.segments.length;
  const links = [], joints = [];
  for (let i = 0; i < nLinks; i++) {
    const l = new THREE.Mesh(new THREE.CylinderGeometry(0.07, 0.09, 1, 14), linkMat);
    scene.add(l);
    links.push(l);
    const j = new THREE.Mesh(new THREE.SphereGeometry(0.1, 14, 10), jointMat);
    scene.add(j);
    joints.push(j);
  }
  const laser = boxMesh([0.06, 0.08, 0.1], 0x1d2a3a);
  laser.matrixAutoUpdate = false;
  scene.add(laser);
  const held = boxMesh(brickSize, 0xb5502b);
  held.matrixAutoUpdate = false;
  scene.add(held);

  // Each visit's cloud, in the site through the pose its registration gave; it appears as the
  // sweep runs (points are in scan order) and stays until the next sweep.
  const visitRows = data.visitsCsv;
  const cloudObjs = [];
  for (const c of clouds) {
    const m = /cloud_visit_(\d+)\.ply/.exec(c.file);
    if (!m || !visitRows) continue;
    const v = Number(m[1]);
    const r = visitRows.col.visit.indexOf(v);
    if (r < 0) continue;
    const loc = visitRows.col.localized[r] === 1 || visitRows.col.localized[r] === 'true';
    const pose = loc ? [visitRows.col.loc_x[r], visitRows.col.loc_y[r], visitRows.col.loc_theta[r]]
      : [visitRows.col.end_x[r], visitRows.col.end_y[r], visitRows.col.end_theta[r]];
    const n = c.xyz_mm.length / 3;
    const pos = new Float32Array(c.xyz_mm.length);
    const cos = Math.cos(pose[2]), sin = Math.sin(pose[2]);
    for (let i = 0; i < n; i++) {
      const x = c.xyz_mm[3 * i] / 1000, y = c.xyz_mm[3 * i + 1] / 1000, z = c.xyz_mm[3 * i + 2] / 1000;
      pos[3 * i] = pose[0] + cos * x - sin * y;
      pos[3 * i + 1] = pose[1] + sin * x + cos * y;
      pos[3 * i + 2] = z;
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    const pts = new THREE.Points(g, new THREE.PointsMaterial({ color: 0x0b6e4f, size: 0.012 }));
    pts.visible = false;
    scene.add(pts);
    const vi = visits.find((x) => x.visit === v);
    const inVisit = sweeps ? sweeps.col.t_on.map((t, i) => [t, sweeps.col.t_off[i]])
      .filter(([on]) => vi && on >= vi.t_start && on <= vi.t_end) : [];
    const last = inVisit.length ? inVisit[inVisit.length - 1] : vi ? [vi.t_start, vi.t_start] : [0, 0];
    cloudObjs.push({ pts, n, on: last[0], off: last[1] });
  }
  cloudObjs.sort((a, b) => a.on - b.on);

  const t = replay.col.t;
  slider.min = 0;
  slider.max = String(Math.max(0, replay.rows - 1));
  slider.step = 1;
  let current = 0;
  const robotPosition = new THREE.Vector3();

  function pose(i) {
    current = Math.max(0, Math.min(replay.rows - 1, i | 0));
    const c = replay.col;
    const T_site_base = planar(c.x[current], c.y[current], c.theta[current]);
    robot.matrixAutoUpdate = false;
    robot.matrix.copy(T_site_base);
    robot.matrixWorldNeedsUpdate = true;
    robotPosition.set(c.x[current], c.y[current], 0);
    const q = [c.q1[current], c.q2[current], c.q3[current], c.q4[current], c.q5[current], c.q6[current]];
    const frames = armFrames(sc.arm, T_site_base, q);
    const p = frames.map((f) => new THREE.Vector3().setFromMatrixPosition(f));
    for (let k = 0; k < nLinks; k++) {
      const a = p[k], b = p[k + 1];
      const len = a.distanceTo(b);
      links[k].visible = len > 1e-3;
      if (len > 1e-3) {
        links[k].position.copy(a).add(b).multiplyScalar(0.5);
        links[k].scale.set(1, len, 1);
        links[k].quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), b.clone().sub(a).normalize());
      }
      joints[k].position.copy(a);
    }
    const tool0 = frames[frames.length - 1];
    laser.matrix.copy(tool0.clone().multiply(mat4(sc.arm.T_tool0_arm_laser)));
    held.visible = c.holding[current] === 1;
    if (held.visible) {
      const g = sc.arm.T_tool0_gripper ? mat4(sc.arm.T_tool0_gripper) : new THREE.Matrix4();
      held.matrix.copy(tool0.clone().multiply(g).multiply(new THREE.Matrix4().makeTranslation(0, 0, brickSize[2] / 2)));
    }
    const standing = c.bricks[current];
    brickMeshes.forEach((m, k) => { m.visible = k < standing; });
    const now = t[current];
    cloudObjs.forEach((o, k) => {
      const next = cloudObjs[k + 1];
      o.pts.visible = now >= o.on && (!next || now < next.on);
      const frac = o.off > o.on ? Math.min(1, (now - o.on) / (o.off - o.on)) : 1;
      o.pts.geometry.setDrawRange(0, Math.ceil(o.n * frac));
    });
    label.textContent = `t = ${now.toFixed(1)} s of ${t[t.length - 1].toFixed(0)} s · base (${c.x[current].toFixed(2)}, ` +
      `${c.y[current].toFixed(2)}) m, ${(c.theta[current] * 180 / Math.PI).toFixed(1)}° · ${standing} bricks standing`;
    render();
  }
  const render = view.render;
  slider.addEventListener('input', () => pose(Number(slider.value)));
  pose(0);
  return {
    setIndex: (i) => { slider.value = String(i); pose(i); },
    robotPosition: () => [robotPosition.x, robotPosition.y, robotPosition.z],
    samples: replay.rows,
    canvas: view.canvas,
    litPixels: view.litPixels,
    render,
  };
}

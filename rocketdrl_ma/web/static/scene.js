// The 3D view in uu with z up, as the physics: the arena mesh the page server exports from
// physics/arena_geometry.py, boost pads, cars built from their hitboxes, the ball and its trail, cameras.
import * as THREE from "three";
import { FLAG_BOOSTING, FLAG_DEMOED, FLAG_SUPERSONIC } from "./timeline.js";

THREE.Object3D.DEFAULT_UP.set(0, 0, 1);

// The game's world is left-handed (a car's "right" axis is its forward turned +90 degrees about up); three.js
// draws right-handed. The scene is the game mirrored in x, so it looks as in the game and a car steering
// right turns right on screen. Game points and rotations go through these two on their way in.
export function toScene(x, y, z) { return [-x, y, z]; }
// The quaternion (x, y, z, w) of rotation R drawn mirrored: M R D with M = diag(-1, 1, 1), D = diag(1, -1, 1)
// (a proper rotation taking the model's forward and up to the mirrored forward and up).
function toSceneQuaternion(x, y, z, w) { return [-y, -x, w, z]; }

export const TEAM_COLORS = [0x2f7bff, 0xff8a1c];
export const TRAIL_POINTS = 24;
// Below MIN_FPS the view draws fewer pixels (down to MIN_PIXEL_RATIO, stretched to the canvas), above
// RECOVER_FPS it draws more again: a slow (software) renderer stays smooth at the cost of sharpness.
const MIN_FPS = 28, RECOVER_FPS = 50, MIN_PIXEL_RATIO = 0.6, PIXEL_STEP = 0.85;
// how far off the view's axis the chased car may be, as a fraction of half the vertical field of view
const CHASE_MAX_OFF_AXIS = 0.7;

// The view's lights: a sky/ground hemisphere and a sun (directions in the drawn, mirrored scene).
const SKY = 0xdde6ff, GROUND = 0x203020, HEMI_INTENSITY = 1.6, SUN_INTENSITY = 1.4, BACKGROUND = 0x0d1117;
const SUN_AT = new THREE.Vector3(-3000, -2000, 8000);

// Those lights' Lambert shading of `color`, worked out once per vertex: the large surfaces (walls, goals) are
// drawn unlit with it, since a software renderer would shade each of their pixels every frame. With `over`, the
// colour is blended over the background colour `over.color` as `over.opacity` would draw it (in sRGB, as the
// canvas blends): an opaque wall that looks translucent wherever only the background is behind it.
function bakeLight(geometry, color, over = null) {
  const normal = geometry.attributes.normal, base = new THREE.Color(color), sun = SUN_AT.clone().normalize();
  const sky = new THREE.Color(SKY), ground = new THREE.Color(GROUND), c = new THREE.Color();
  const out = new Float32Array(normal.count * 3);
  const back = over ? new THREE.Color(over.color).convertLinearToSRGB() : null, mixed = new THREE.Color();
  for (let i = 0; i < normal.count; i++) {
    const nx = normal.getX(i), ny = normal.getY(i), nz = normal.getZ(i);
    const direct = (SUN_INTENSITY / Math.PI) * Math.max(0, nx * sun.x + ny * sun.y + nz * sun.z);
    c.copy(ground).lerp(sky, 0.5 * nz + 0.5).multiplyScalar(HEMI_INTENSITY / Math.PI).addScalar(direct).multiply(base);
    if (over) c.copy(mixed.copy(back).lerp(c.convertLinearToSRGB(), over.opacity)).convertSRGBToLinear();
    out[3 * i] = c.r; out[3 * i + 1] = c.g; out[3 * i + 2] = c.b;
  }
  geometry.setAttribute("color", new THREE.BufferAttribute(out, 3));
  return geometry;
}

function arenaMeshes(arena) {
  // Colour the physics' triangles by where they are: floor, goal boxes (by team) and the rest of the shell.
  const v = arena.vertices.map((value, i) => (i % 3 === 0 ? -value : value)), backY = arena.field.extent_y;
  const tris = arena.triangles.map((id, i, all) => (i % 3 === 1 ? all[i + 1] : i % 3 === 2 ? all[i - 1] : id));
  const groups = { floor: [], shell: [], goal0: [], goal1: [] };
  for (let i = 0; i < tris.length; i += 3) {
    const ids = [tris[i], tris[i + 1], tris[i + 2]];
    const zs = ids.map((k) => v[3 * k + 2]), ys = ids.map((k) => v[3 * k + 1]);
    let group = "shell";
    if (zs.every((z) => z < 1)) group = "floor";
    else if (ys.every((y) => y >= backY - 1)) group = "goal1";   // orange defends +y
    else if (ys.every((y) => y <= -backY + 1)) group = "goal0";  // blue defends -y
    groups[group].push(...ids);
  }
  const positions = new THREE.Float32BufferAttribute(v, 3);
  const make = (ids) => {
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", positions);
    g.setIndex(ids);
    g.computeVertexNormals();
    return g;
  };
  const out = new THREE.Group();
  // the floor is flat: one colour, no per-pixel lighting (the largest area on screen; software renderers care)
  out.add(new THREE.Mesh(make(groups.floor), new THREE.MeshBasicMaterial({ color: 0x2f5e3c })));
  // Faces point into the field: from a camera outside it, the near walls and the ceiling are culled away. Only the
  // background is behind the walls seen, so they are drawn opaque in the colour a 28% translucent wall would show:
  // no blending, and what is behind them is never drawn.
  out.add(new THREE.Mesh(bakeLight(make(groups.shell), 0x7d8fb3, { color: BACKGROUND, opacity: 0.28 }),
    new THREE.MeshBasicMaterial({ vertexColors: true })));
  for (const team of [0, 1]) {
    out.add(new THREE.Mesh(bakeLight(make(groups[`goal${team}`]), TEAM_COLORS[team]), new THREE.MeshBasicMaterial({
      vertexColors: true, transparent: true, opacity: 0.45, depthWrite: false, side: THREE.DoubleSide })));
  }
  const edges = new THREE.EdgesGeometry(make([...groups.shell, ...groups.goal0, ...groups.goal1]), 25);
  out.add(new THREE.LineSegments(edges, new THREE.LineBasicMaterial({ color: 0xb8c4dd, transparent: true,
    opacity: 0.35 })));
  return out;
}

function fieldLines(arena) {
  const pts = [], x = arena.field.extent_x - 420, y = arena.field.extent_y - 420, z = 2;
  pts.push(-x, 0, z, x, 0, z);
  for (let i = 0; i < 64; i++) {
    const a = (i / 64) * 2 * Math.PI, b = ((i + 1) / 64) * 2 * Math.PI;
    pts.push(1000 * Math.cos(a), 1000 * Math.sin(a), z, 1000 * Math.cos(b), 1000 * Math.sin(b), z);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", new THREE.Float32BufferAttribute(pts, 3));
  return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0xcfe8d6, transparent: true, opacity: 0.5 }));
}

const PAD_LIT = new THREE.Color(0xffc93c), PAD_TAKEN = new THREE.Color(0x3a3f47);
const HIDDEN = new THREE.Matrix4().makeScale(0, 0, 0);

// The boost pads as three instanced meshes (small pads, big pads, big pads' orbs): three draw calls, not forty.
function makePads(arena) {
  const group = new THREE.Group(), pads = [];
  const counts = [arena.pads.filter((p) => !p[3]).length, arena.pads.filter((p) => p[3]).length];
  const [small, big] = [false, true].map((isBig, k) => {
    const r = isBig ? arena.pad_radius.big * 0.5 : arena.pad_radius.small * 0.45;
    const disc = new THREE.CylinderGeometry(r, r, 10, isBig ? 24 : 12).rotateX(Math.PI / 2);
    return new THREE.InstancedMesh(disc, new THREE.MeshBasicMaterial(), counts[k]);
  });
  const orbs = new THREE.InstancedMesh(new THREE.SphereGeometry(60, 16, 12),
    new THREE.MeshBasicMaterial({ color: 0xffb020, transparent: true, opacity: 0.75 }), counts[1]);
  const used = new Map([[small, 0], [big, 0]]);
  for (const [x, y, , isBig] of arena.pads) {
    const mesh = isBig ? big : small, at = used.get(mesh);
    used.set(mesh, at + 1);
    mesh.setMatrixAt(at, new THREE.Matrix4().makeTranslation(...toScene(x, y, 6)));
    mesh.setColorAt(at, PAD_LIT);
    const orb = isBig ? { at, matrix: new THREE.Matrix4().makeTranslation(...toScene(x, y, 120)) } : null;
    if (orb) orbs.setMatrixAt(at, orb.matrix);
    pads.push({ mesh, at, orb, lit: true });
  }
  group.add(small, big, orbs);
  return { group, pads, orbs };
}

// Parts [geometry, matrix, colour] as one geometry with vertex colours: one draw call for a car's body.
function mergeParts(parts) {
  const positions = [], normals = [], colors = [];
  for (const [geometry, matrix, color] of parts) {
    const g = geometry.toNonIndexed().applyMatrix4(matrix);
    const c = new THREE.Color(color);
    positions.push(...g.attributes.position.array);
    normals.push(...g.attributes.normal.array);
    for (let i = 0; i < g.attributes.position.count; i++) colors.push(c.r, c.g, c.b);
  }
  const merged = new THREE.BufferGeometry();
  merged.setAttribute("position", new THREE.Float32BufferAttribute(positions, 3));
  merged.setAttribute("normal", new THREE.Float32BufferAttribute(normals, 3));
  merged.setAttribute("color", new THREE.Float32BufferAttribute(colors, 3));
  return merged;
}

// A car from its hitbox (length, width, height, offset): body, cabin, nose, wheels, boost flame.
function makeCar(hitbox, team) {
  const [l, w, h, ox, oy, oz] = hitbox;
  const paint = new THREE.Color(TEAM_COLORS[team]).lerp(new THREE.Color(0xffffff), 0.15);
  const white = 0xf4f7fb, dark = 0x1b2330, tyre = 0x111111;
  const at = (x, y, z) => new THREE.Matrix4().makeTranslation(x, y, z);
  // body, cabin, the white stripe and nose that show the heading at a glance, spoiler, wheels
  const parts = [
    [new THREE.BoxGeometry(l, w, h * 0.55), at(0, 0, -h * 0.12), paint],
    [new THREE.BoxGeometry(l * 0.45, w * 0.8, h * 0.45), at(-l * 0.1, 0, h * 0.3), dark],
    [new THREE.BoxGeometry(l * 0.5, w * 0.18, h * 0.04), at(l * 0.24, 0, h * 0.17), white],
    [new THREE.BoxGeometry(l * 0.06, w * 0.9, h * 0.3), at(l * 0.49, 0, -h * 0.12), white],
    [new THREE.BoxGeometry(l * 0.08, w, h * 0.12), at(-l * 0.47, 0, h * 0.32), paint],
  ];
  for (const sx of [0.32, -0.32]) for (const sy of [0.5, -0.5]) {
    parts.push([new THREE.CylinderGeometry(h * 0.42, h * 0.42, w * 0.18, 14), at(sx * l, sy * w, -h * 0.35), tyre]);
  }
  const car = new THREE.Group();
  const body = new THREE.Group();
  body.position.set(ox, oy, oz);
  car.add(body);
  body.add(new THREE.Mesh(mergeParts(parts), new THREE.MeshLambertMaterial({ vertexColors: true,
    emissive: TEAM_COLORS[team], emissiveIntensity: 0.25 })));
  const flame = new THREE.Mesh(new THREE.ConeGeometry(w * 0.2, l * 0.7, 12),
    new THREE.MeshBasicMaterial({ color: 0xffa53a, transparent: true, opacity: 0.85,
      blending: THREE.AdditiveBlending, depthWrite: false }));
  flame.rotation.z = Math.PI / 2; // the cone's tip (+y) points backwards (-x)
  flame.position.set(-l * 0.5 - l * 0.33, 0, -h * 0.05);
  flame.visible = false;
  body.add(flame);
  const wreck = new THREE.Mesh(new THREE.SphereGeometry(l * 0.6, 12, 10),
    new THREE.MeshBasicMaterial({ color: 0x555555, transparent: true, opacity: 0.5, depthWrite: false }));
  wreck.visible = false;
  return { car, body, flame, wreck, demoedAt: null };
}

export class View {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: false, powerPreference: "high-performance" });
    this.maxPixelRatio = Math.min(window.devicePixelRatio || 1, 1.5);
    this.renderer.setPixelRatio(this.maxPixelRatio);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(BACKGROUND);
    this.scene.add(new THREE.HemisphereLight(SKY, GROUND, HEMI_INTENSITY));
    const sun = new THREE.DirectionalLight(0xffffff, SUN_INTENSITY);
    sun.position.copy(SUN_AT);
    this.scene.add(sun);
    this.camera = new THREE.PerspectiveCamera(55, 1, 20, 40000);
    this.cameraMode = "broadcast";
    this.chaseIndex = 0;
    this.ballCam = true;
    // the orbit camera: around the ball, turned and zoomed with the mouse (radians, uu)
    this.orbit = { yaw: 0.6, pitch: 0.45, distance: 3200 };
    this.cars = [];
    this.roster = null;
    this.camTarget = new THREE.Vector3();
    this.camPos = new THREE.Vector3(-9000, 0, 4500);
    this.obstacles = new THREE.Group();
    this.scene.add(this.obstacles);
  }

  setArena(arena) {
    this.arena = arena;
    this.scene.add(arenaMeshes(arena));
    this.scene.add(fieldLines(arena));
    const { group, pads, orbs } = makePads(arena);
    this.scene.add(group);
    this.pads = pads;
    this.orbs = orbs;
    const r = arena.ball_radius;
    this.ball = new THREE.Mesh(new THREE.SphereGeometry(r, 24, 16),
      new THREE.MeshLambertMaterial({ color: 0xf2f2f2, emissive: 0x555555 }));
    this.scene.add(this.ball);
    this.ballShadow = new THREE.Mesh(new THREE.CircleGeometry(r, 24),
      new THREE.MeshBasicMaterial({ color: 0x000000, transparent: true, opacity: 0.35, depthWrite: false }));
    this.ballShadow.position.z = 3;
    this.scene.add(this.ballShadow);
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(new Float32Array(TRAIL_POINTS * 3), 3));
    g.setAttribute("color", new THREE.Float32BufferAttribute(new Float32Array(TRAIL_POINTS * 3), 3));
    this.trailLine = new THREE.Line(g, new THREE.LineBasicMaterial({ vertexColors: true, transparent: true }));
    this.trailLine.frustumCulled = false;
    this.scene.add(this.trailLine);
  }

  setRoster(roster) {
    for (const c of this.cars) { this.scene.remove(c.car); this.scene.remove(c.wreck); }
    this.roster = roster;
    this.cars = roster.agents.map((_, i) => {
      const c = makeCar(roster.hitboxes[i], roster.teams[i]);
      this.scene.add(c.car);
      this.scene.add(c.wreck);
      return c;
    });
    this.chaseIndex = Math.min(this.chaseIndex, Math.max(0, this.cars.length - 1));
  }

  // Turn the orbit camera by a mouse drag (CSS pixels) or zoom it by a wheel step.
  turnOrbit(dx, dy) {
    this.orbit.yaw -= dx * 0.006;
    this.orbit.pitch = THREE.MathUtils.clamp(this.orbit.pitch + dy * 0.006, 0.05, 1.5);
  }

  zoomOrbit(steps) { this.orbit.distance = THREE.MathUtils.clamp(this.orbit.distance * 1.1 ** steps, 600, 12000); }

  setCamera(mode, index) {
    this.cameraMode = mode;
    if (index !== undefined) this.chaseIndex = index;
  }

  // Fewer or more pixels for the frame rate `fps` the page measured over the last seconds.
  adaptResolution(fps) {
    const now = this.renderer.getPixelRatio();
    let next = now;
    if (fps < MIN_FPS) next = Math.max(MIN_PIXEL_RATIO, now * PIXEL_STEP);
    else if (fps > RECOVER_FPS) next = Math.min(this.maxPixelRatio, now / PIXEL_STEP);
    if (Math.abs(next - now) > 1e-3) this.renderer.setPixelRatio(next);
  }

  resize() {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    if (this.canvas.width !== Math.floor(w * this.renderer.getPixelRatio()) || this._h !== h) {
      this.renderer.setSize(w, h, false);
      this.camera.aspect = w / Math.max(h, 1);
      this.camera.updateProjectionMatrix();
      this._h = h;
    }
  }

  // Draw the sampled state `s` (timeline.sample) at wall time `now` (s).
  // `trail`: the ball's recent positions, newest first.
  draw(s, now, dt, trail) {
    this.resize();
    if (s && this.ball) this.apply(s, now, trail);
    this.updateCamera(s, dt);
    this.renderer.render(this.scene, this.camera);
  }

  apply(s, now, trailPoints) {
    const [bx, by, bz] = toScene(...s.b);
    this.ball.position.set(bx, by, bz);
    this.ballShadow.position.set(bx, by, 3);
    this.ballShadow.material.opacity = Math.max(0.08, 0.4 - bz / 5000);
    const pos = this.trailLine.geometry.attributes.position, col = this.trailLine.geometry.attributes.color;
    const trail = trailPoints || [];
    for (let i = 0; i < TRAIL_POINTS; i++) {
      const p = trail.length ? toScene(...trail[Math.min(i, trail.length - 1)]) : [bx, by, bz]; // newest first
      const k = 1 - Math.min(i, trail.length - 1) / TRAIL_POINTS;
      pos.setXYZ(i, p[0], p[1], p[2]);
      col.setXYZ(i, 0.05 + 0.9 * k, 0.05 + 0.85 * k, 0.08 + 0.6 * k);
    }
    pos.needsUpdate = true; col.needsUpdate = true;
    if (this.pads && s.p !== this.padMask) {
      this.padMask = s.p;
      const mask = BigInt(s.p);
      this.pads.forEach((p, i) => {
        const lit = ((mask >> BigInt(i)) & 1n) === 1n;
        if (lit === p.lit) return;
        p.lit = lit;
        p.mesh.setColorAt(p.at, lit ? PAD_LIT : PAD_TAKEN);
        p.mesh.instanceColor.needsUpdate = true;
        if (p.orb) {
          this.orbs.setMatrixAt(p.orb.at, lit ? p.orb.matrix : HIDDEN);
          this.orbs.instanceMatrix.needsUpdate = true;
        }
      });
    }
    this.cars.forEach((c, i) => {
      const car = s.a[i];
      if (!car) { c.car.visible = false; c.wreck.visible = false; return; }
      const demoed = (car[8] & FLAG_DEMOED) !== 0;
      if (demoed) {
        if (c.demoedAt === null) { c.demoedAt = now; c.wreck.position.copy(c.car.position); }
        const age = now - c.demoedAt;
        c.car.visible = false;
        c.wreck.visible = age < 1.2;
        c.wreck.scale.setScalar(1 + age * 1.5);
        c.wreck.material.opacity = Math.max(0, 0.55 - age * 0.45);
        return;
      }
      c.demoedAt = null;
      c.wreck.visible = false;
      c.car.visible = true;
      c.car.position.set(...toScene(car[0], car[1], car[2]));
      c.car.quaternion.set(...toSceneQuaternion(car[3], car[4], car[5], car[6]));
      const boosting = (car[8] & FLAG_BOOSTING) !== 0;
      c.flame.visible = boosting;
      if (boosting) {
        const flicker = 0.85 + 0.3 * Math.sin(now * 60 + i);
        const fast = (car[8] & FLAG_SUPERSONIC) !== 0 ? 1.3 : 1;
        c.flame.scale.set(1, flicker * fast, 1);
      }
    });
  }

  // Where a game point (uu) is drawn, in CSS pixels from the canvas' top left; null when behind the camera.
  screenPoint(point) {
    const v = new THREE.Vector3(...toScene(...point)).project(this.camera);
    return v.z > 1 ? null : [((v.x + 1) / 2) * this.canvas.clientWidth, ((1 - v.y) / 2) * this.canvas.clientHeight];
  }

  // Where a game point (uu) is on the canvas, in CSS pixels from its top left.
  project([x, y, z]) {
    const v = new THREE.Vector3(...toScene(x, y, z)).project(this.camera);
    return [((v.x + 1) / 2) * this.canvas.clientWidth, ((1 - v.y) / 2) * this.canvas.clientHeight];
  }

  setObstacles(list) {
    const key = JSON.stringify(list || []);
    if (key === this._obstacleKey) return;
    this._obstacleKey = key;
    this.obstacles.clear();
    for (const [cx, cy, cz, hx, hy, hz] of list || []) {
      const box = new THREE.Mesh(new THREE.BoxGeometry(2 * hx, 2 * hy, 2 * hz),
        new THREE.MeshLambertMaterial({ color: 0x9aa4b2, transparent: true, opacity: 0.6 }));
      box.position.set(...toScene(cx, cy, cz));
      this.obstacles.add(box);
    }
  }

  updateCamera(s, dt) {
    const cam = this.camera, ball = this.ball ? this.ball.position : new THREE.Vector3();
    const follow = 1 - Math.exp(-dt * 4);
    let pos, target, up = new THREE.Vector3(0, 0, 1);
    const chased = this.cameraMode === "chase" && this.cars[this.chaseIndex];
    if (this.cameraMode === "orbit") {
      const { yaw, pitch, distance } = this.orbit;
      target = new THREE.Vector3().copy(ball);
      pos = new THREE.Vector3(ball.x + distance * Math.cos(pitch) * Math.cos(yaw),
        ball.y + distance * Math.cos(pitch) * Math.sin(yaw), Math.max(40, ball.z + distance * Math.sin(pitch)));
    } else if (this.cameraMode === "top") {
      // high enough to fit the field and both goals, the field's length across the screen
      const halfLength = this.arena ? this.arena.field.extent_y + this.arena.goal.depth : 6000;
      const halfWidth = this.arena ? this.arena.field.extent_x + 200 : 4300;
      const tanV = Math.tan(THREE.MathUtils.degToRad(cam.fov / 2)), tanH = tanV * cam.aspect;
      pos = new THREE.Vector3(0, 0, Math.max(halfLength / tanH, halfWidth / tanV) + 200);
      target = new THREE.Vector3(0, 0, 0);
      up = new THREE.Vector3(-1, 0, 0); // the field's length across the screen, blue's goal on the left
    } else if (chased && chased.car.visible) {
      const car = chased.car.position;
      // ball cam: behind the car on the line from the ball; car cam: behind the car's heading
      const heading = new THREE.Vector3(1, 0, 0).applyQuaternion(chased.car.quaternion);
      const away = this.ballCam ? new THREE.Vector3(car.x - ball.x, car.y - ball.y, 0)
        : new THREE.Vector3(-heading.x, -heading.y, 0);
      if (away.lengthSq() < 1) away.set(-1, 0, 0);
      away.normalize();
      pos = new THREE.Vector3(car.x + away.x * 750, car.y + away.y * 750, car.z + 320);
      if (this.arena) { // stay on the field's side of the walls (a camera box, not the arena's shape)
        const f = this.arena.field;
        pos.set(THREE.MathUtils.clamp(pos.x, 150 - f.extent_x, f.extent_x - 150),
          THREE.MathUtils.clamp(pos.y, 150 - f.extent_y, f.extent_y - 150),
          THREE.MathUtils.clamp(pos.z, 60, f.height - 100));
      }
      target = this.ballCam ? new THREE.Vector3().copy(ball).lerp(car, 0.25)
        : new THREE.Vector3().copy(car).addScaledVector(away, -1500);
    } else {
      // beside the field (+x, so blue's goal is on the left), level with the ball along its length
      pos = new THREE.Vector3(ball.x * 0.35 + 5600, ball.y * 0.8, 2600 + ball.z * 0.3);
      target = new THREE.Vector3(ball.x * 0.75, ball.y * 0.92, 100 + ball.z * 0.5);
    }
    const snap = this.cameraMode !== this._lastMode;
    this._lastMode = this.cameraMode;
    this.camPos.lerp(pos, snap ? 1 : follow);
    this.camTarget.lerp(target, snap ? 1 : follow);
    if (chased && chased.car.visible) this.keepInView(chased.car.position);
    cam.position.copy(this.camPos);
    cam.up.copy(up);
    cam.lookAt(this.camTarget);
  }

  // Turn the camera's aim towards `point` until it is within CHASE_MAX_OFF_AXIS of the vertical field of view
  // from the centre: a ball high above would otherwise take the chased car off the bottom of the screen.
  keepInView(point) {
    const toPoint = new THREE.Vector3().subVectors(point, this.camPos);
    const aim = new THREE.Vector3().subVectors(this.camTarget, this.camPos);
    if (toPoint.lengthSq() < 1 || aim.lengthSq() < 1) return;
    const distance = aim.length();
    toPoint.normalize(); aim.normalize();
    const limit = CHASE_MAX_OFF_AXIS * THREE.MathUtils.degToRad(this.camera.fov / 2);
    const angle = toPoint.angleTo(aim);
    if (angle <= limit) return;
    const turn = new THREE.Quaternion().setFromUnitVectors(toPoint, aim);
    const partial = new THREE.Quaternion().slerp(turn, limit / angle);
    this.camTarget.copy(this.camPos).addScaledVector(toPoint.applyQuaternion(partial), distance);
  }
}

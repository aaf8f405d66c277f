// Frames on a tick axis and a playhead that moves along it: the page draws the state interpolated at the
// playhead, so motion is smooth at the display's rate whatever the rate of the states (at most 30 a second).
// Live: the playhead follows the newest frame about LIVE_LAG_S behind, its speed adapting to the rate the
// ticks arrive at; a player's own match is drawn at its newest frame (their keys' effect as soon as it arrives).
// A spectator may leave the live edge (pause, seek and step within the last LIVE_KEEP_S, or an instant replay)
// and come back to it. Replay: it moves at the replay's tick rate times the chosen speed, and seeks and steps.

const LIVE_LAG_S = 0.12;
const LIVE_KEEP_S = 60;
const LIVE_KEEP_EVENTS = 500;
const TELEPORT_UU = 1200; // a car or the ball that jumped further than this between frames is not interpolated

export const FLAG_DEMOED = 1, FLAG_BOOSTING = 2, FLAG_SUPERSONIC = 4;

function lerp(a, b, t) { return a + (b - a) * t; }

function slerp(qa, qb, t) {
  let [ax, ay, az, aw] = qa, [bx, by, bz, bw] = qb;
  let cos = ax * bx + ay * by + az * bz + aw * bw;
  if (cos < 0) { bx = -bx; by = -by; bz = -bz; bw = -bw; cos = -cos; }
  let ka = 1 - t, kb = t;
  if (cos < 0.9995) {
    const angle = Math.acos(cos), sin = Math.sin(angle);
    ka = Math.sin((1 - t) * angle) / sin; kb = Math.sin(t * angle) / sin;
  }
  const x = ka * ax + kb * bx, y = ka * ay + kb * by, z = ka * az + kb * bz, w = ka * aw + kb * bw;
  const n = Math.hypot(x, y, z, w) || 1;
  return [x / n, y / n, z / n, w / n];
}

// An event with the match clock of the frame that brought it (the scoreboard's time, not the physics' tick).
function onClock(event, frame) { return { ...event, clock: frame.c, overtime: frame.o }; }

function far(a, b) { return Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]) > TELEPORT_UU; }

// The frames around `tick` and how far between them it is: [a, b, t], or null with no frames.
function around(frames, tick) {
  if (!frames.length) return null;
  let lo = 0, hi = frames.length - 1;
  if (tick <= frames[0].t) return [frames[0], frames[0], 0];
  if (tick >= frames[hi].t) return [frames[hi], frames[hi], 0];
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (frames[mid].t <= tick) lo = mid; else hi = mid;
  }
  return [frames[lo], frames[hi], (tick - frames[lo].t) / (frames[hi].t - frames[lo].t)];
}

function ballAt(a, b, t) {
  return far(a.b, b.b) ? (t < 0.5 ? a.b : b.b) : a.b.map((v, i) => lerp(v, b.b[i], t));
}

// The state at `tick` between the frames around it (the earlier frame's discrete fields).
export function sample(frames, tick) {
  const found = around(frames, tick);
  if (!found) return null;
  const [a, b, t] = found;
  if (a === b) return { ...a, alpha: 0 };
  const ball = ballAt(a, b, t);
  const cars = a.a.map((ca, i) => {
    const cb = b.a[i];
    if (!ca || !cb) return t < 0.5 ? ca : cb;
    if ((ca[8] | cb[8]) & FLAG_DEMOED || far(ca, cb)) return t < 0.5 ? ca : cb;
    const q = slerp(ca.slice(3, 7), cb.slice(3, 7), t);
    return [lerp(ca[0], cb[0], t), lerp(ca[1], cb[1], t), lerp(ca[2], cb[2], t), ...q, lerp(ca[7], cb[7], t),
      t < 0.5 ? ca[8] : cb[8]];
  });
  return { ...a, b: ball, a: cars, alpha: t };
}

export class Timeline {
  constructor() { this.reset(); }

  reset() {
    this.frames = [];
    this.events = [];
    this.playhead = 0;
    this.live = false;
    this.playing = false;
    this.speed = 1;
    this.tickRate = 120;
    this.ticksPerS = null;   // live: measured arrival rate of ticks
    this.lastArrival = 0;
    this.arrivalGap = 1 / 15;
    this.ended = false;
    this.follow = true;       // live: the playhead follows the newest frame (false: paused or rewound)
    this.replayUntil = null;  // live: an instant replay's last tick, then back to the newest frame
  }

  // ------------------------------------------------------------------ live
  // `asPlayer`: the page plays in this match (a shorter live lag)
  startLive(asPlayer = false) { this.reset(); this.live = true; this.playing = true; this.asPlayer = asPlayer; }

  pushLive(frame, now) {
    const last = this.frames[this.frames.length - 1];
    if (last && frame.t < last.t) { // a new episode (a training run's next evaluation): start over
      this.frames = []; this.events = []; this.ticksPerS = null;
    }
    if (last && frame.t === last.t) { this.frames[this.frames.length - 1] = frame; }
    else this.frames.push(frame);
    this.tickRate = frame.r || this.tickRate;
    for (const e of frame.e || []) this.events.push(onClock(e, frame));
    if (last && frame.t > last.t && this.lastArrival) {
      const gap = Math.max(now - this.lastArrival, 1e-3);
      const rate = (frame.t - last.t) / gap;
      this.ticksPerS = this.ticksPerS === null ? rate : 0.85 * this.ticksPerS + 0.15 * rate;
      this.arrivalGap = 0.85 * this.arrivalGap + 0.15 * gap;
    }
    if (this.frames.length === 1) this.playhead = frame.t;
    this.lastArrival = now;
    const keepTicks = LIVE_KEEP_S * Math.max(this.ticksPerS || this.tickRate, this.tickRate);
    while (this.frames.length > 2 && this.frames[0].t < frame.t - keepTicks) this.frames.shift();
    while (this.events.length > LIVE_KEEP_EVENTS) this.events.shift();
    if (this.playhead < this.firstTick) this.playhead = this.firstTick; // paused past the buffer's start
  }

  // Live: how far behind the newest state the playhead aims to be, in seconds. A player sees the newest state
  // (no jitter buffer: their input's effect drawn at once, at the cost of a stutter when a state comes late);
  // a spectator LIVE_LAG_S behind, for smooth motion.
  lagS() { return this.asPlayer ? 0 : LIVE_LAG_S; }

  // Live: leave the live edge where the playhead is (paused, or moved by seek and step) ...
  holdLive() { this.follow = false; this.replayUntil = null; }

  // ... and follow the newest frame again.
  goLive() {
    this.follow = true; this.playing = true; this.speed = 1; this.replayUntil = null;
    this.playhead = Math.max(this.firstTick, this.lastTick - this.lagS() * (this.ticksPerS || this.tickRate));
  }

  // Live: play the buffer's [fromTick, untilTick] again at normal speed, then follow the newest frame again.
  instantReplay(fromTick, untilTick) {
    this.follow = false; this.playing = true; this.speed = 1;
    this.playhead = Math.max(fromTick, this.firstTick);
    this.replayUntil = untilTick;
  }

  get replaying() { return this.live && this.replayUntil !== null; }

  addEvents(events) {
    const last = this.frames[this.frames.length - 1];
    for (const e of events || []) this.events.push(last ? onClock(e, last) : e);
  }

  // ------------------------------------------------------------------ replay
  loadReplay(frames, tickRate) {
    this.reset();
    this.frames = frames;
    this.tickRate = tickRate || 120;
    this.events = frames.flatMap((f) => (f.e || []).map((e) => onClock(e, f)));
    this.playhead = frames.length ? frames[0].t : 0;
    this.playing = true;
  }

  get firstTick() { return this.frames.length ? this.frames[0].t : 0; }
  get lastTick() { return this.frames.length ? this.frames[this.frames.length - 1].t : 0; }

  seek(tick) { this.playhead = Math.min(Math.max(tick, this.firstTick), this.lastTick); }

  // One decision (recorded state) forward or back from the playhead.
  step(direction) {
    if (this.live) this.holdLive();
    this.playing = false;
    const f = this.frames;
    if (!f.length) return;
    if (direction > 0) {
      const next = f.find((x) => x.t > this.playhead + 1e-6);
      this.playhead = next ? next.t : this.lastTick;
    } else {
      let prev = null;
      for (const x of f) { if (x.t < this.playhead - 1e-6) prev = x; else break; }
      this.playhead = prev ? prev.t : this.firstTick;
    }
  }

  // ------------------------------------------------------------------ both
  advance(dt, now) {
    if (!this.frames.length) return;
    if (this.live && this.follow && this.asPlayer) {
      this.playhead = this.lastTick;
    } else if (this.live && this.follow) {
      const rate = this.ticksPerS || this.tickRate;
      const quiet = now - this.lastArrival > 2.5 * this.arrivalGap + 0.05; // nothing new: show the newest
      const target = quiet ? this.lastTick : this.lastTick - this.lagS() * rate;
      const error = target - this.playhead;
      if (Math.abs(error) > rate * 1.0) this.playhead = target; // far behind or ahead: jump
      else this.playhead += dt * rate * Math.min(2, Math.max(0.25, 1 + error / (rate * 0.25)));
      this.playhead = Math.min(this.playhead, this.lastTick);
    } else if (this.playing) {
      this.playhead += dt * this.tickRate * this.speed;
      if (this.live && this.playhead >= Math.min(this.lastTick, this.replayUntil ?? Infinity)) this.goLive();
      else if (this.playhead >= this.lastTick) { this.playhead = this.lastTick; this.playing = false; }
    }
  }

  current() { return sample(this.frames, this.playhead); }

  // The ball's positions over the last `seconds` of game time before the playhead, newest first, cut where
  // it jumped (a reset after a goal).
  trail(points, seconds) {
    const out = [], step = (seconds * this.tickRate) / points;
    for (let i = 0; i < points; i++) {
      const tick = this.playhead - i * step;
      if (tick < this.firstTick) break;
      const [a, b, t] = around(this.frames, tick);
      const p = ballAt(a, b, t);
      if (out.length && far(out[out.length - 1], p)) break;
      out.push(p);
    }
    return out;
  }

  // The frame index at or before the playhead (the timeline's "decision").
  index() {
    const f = this.frames;
    let lo = 0, hi = f.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (f[mid].t <= this.playhead + 1e-6) lo = mid; else hi = mid - 1;
    }
    return lo;
  }

  shownEvents(n) {
    return this.events.filter((e) => e.tick <= this.playhead + 1e-6).slice(-n);
  }
}

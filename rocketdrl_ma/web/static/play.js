// A human's controls: the keyboard (bindings like the game's, rebindable, kept in this browser) and any
// gamepad (the Gamepad API's standard mapping), read every frame into the 8 controls of the continuous
// action format: throttle, steer, pitch, yaw, roll, jump, boost, handbrake.

export const BINDABLE = [
  ["forward", "throttle / nose down"], ["reverse", "reverse / nose up"], ["left", "steer left"],
  ["right", "steer right"], ["jump", "jump (again: dodge)"], ["boost", "boost"],
  ["powerslide", "powerslide / air roll"], ["rollLeft", "air roll left"], ["rollRight", "air roll right"],
  ["ballCam", "ball cam on/off"],
];
export const DEFAULT_KEYS = {
  forward: "KeyW", reverse: "KeyS", left: "KeyA", right: "KeyD", jump: "Space", boost: "ShiftLeft",
  powerslide: "KeyX", rollLeft: "KeyQ", rollRight: "KeyE", ballCam: "KeyC",
};
const STORAGE_KEY = "rocketdrl-ma.keys";
const STICK_DEADZONE = 0.15;
// standard mapping: A jump, B boost, X powerslide / air roll, Y ball cam, LB / RB air roll, LT / RT reverse / throttle
const PAD = { jump: 0, boost: 1, powerslide: 2, ballCam: 3, rollLeft: 4, rollRight: 5, reverse: 6, forward: 7 };

function clamp1(v) { return Math.max(-1, Math.min(1, v)); }
function stick(v) { return Math.abs(v) < STICK_DEADZONE ? 0 : v; }

export class Controls {
  constructor() {
    this.keys = { ...DEFAULT_KEYS, ...JSON.parse(localStorage.getItem(STORAGE_KEY) || "{}") };
    this.down = new Set();
    this.padBallCam = false;
    this.onBallCam = () => {};
  }

  bind(action, code) {
    this.keys[action] = code;
    localStorage.setItem(STORAGE_KEY, JSON.stringify(this.keys));
  }

  resetBindings() { this.keys = { ...DEFAULT_KEYS }; localStorage.removeItem(STORAGE_KEY); }

  // true when the key is one of the bindings (the page then keeps it from scrolling or playing a replay)
  keyDown(code) {
    if (code === this.keys.ballCam && !this.down.has(code)) this.onBallCam();
    this.down.add(code);
    return Object.values(this.keys).includes(code);
  }

  keyUp(code) { this.down.delete(code); }

  releaseAll() { this.down.clear(); }

  pressed(action) { return this.down.has(this.keys[action]); }

  // The controls now, keyboard and the first connected gamepad together.
  read() {
    const key = (a) => (this.pressed(a) ? 1 : 0);
    let throttle = key("forward") - key("reverse"), steer = key("right") - key("left");
    let pitch = key("reverse") - key("forward"), roll = key("rollRight") - key("rollLeft");
    let jump = key("jump"), boost = key("boost"), slide = key("powerslide");
    const pad = [...(navigator.getGamepads ? navigator.getGamepads() : [])].find((p) => p && p.connected);
    if (pad) {
      const button = (i) => (pad.buttons[i] ? pad.buttons[i].value : 0);
      throttle += button(PAD.forward) - button(PAD.reverse);
      steer += stick(pad.axes[0] || 0);
      pitch += stick(pad.axes[1] || 0);
      roll += (button(PAD.rollRight) > 0.5 ? 1 : 0) - (button(PAD.rollLeft) > 0.5 ? 1 : 0);
      jump = Math.max(jump, button(PAD.jump) > 0.5 ? 1 : 0);
      boost = Math.max(boost, button(PAD.boost) > 0.5 ? 1 : 0);
      slide = Math.max(slide, button(PAD.powerslide) > 0.5 ? 1 : 0);
      const cam = button(PAD.ballCam) > 0.5;
      if (cam && !this.padBallCam) this.onBallCam();
      this.padBallCam = cam;
    }
    steer = clamp1(steer);
    // powerslide held in the air turns steering into roll, as in the game
    if (slide && roll === 0) roll = steer;
    return [clamp1(throttle), steer, clamp1(pitch), slide ? 0 : steer, clamp1(roll), jump ? 1 : -1,
      boost ? 1 : -1, slide ? 1 : -1];
  }
}

// The page: lists what can be watched, follows one source over the websocket, draws it and its HUD.
// Watching sends only list, watch, replay and stop; a page server started with --play also takes a seat
// for this page (play, then input: its own car's controls, and leave).
import { decode } from "@msgpack/msgpack";
import { BINDABLE, Controls } from "./play.js";
import { TRAIL_POINTS, View } from "./scene.js";
import { FLAG_DEMOED, Timeline } from "./timeline.js";

const $ = (id) => document.getElementById(id);
// `?sharp` in the page's address: always the full pixel ratio, however slowly it draws
const SHARP = new URLSearchParams(location.search).has("sharp");
const view = new View($("view"));
const timeline = new Timeline();
const stats = { frames: 0, bytesLast: 0, bytesMax: 0, arrivals: [], renders: [], busyMs: [] };
let boostPanels = [];
let socket = null, roster = null, source = null, lastList = null, status = null, hudHidden = false;
const controls = new Controls();
// this page's seat: {match, slot}; sent: the last controls sent and when each unanswered input left
let seat = null, sent = null, inputSeq = 0, rebinding = null;
const inputSentAt = new Map(), ackMs = [];
// the last inputs' times (performance.now, ms): the key event, the send, the page server's ack; and the last
// frames' ticks with their arrival: the latency benchmark lines them up with the servers' own times
const inputTimes = [], frameArrivals = [];
const TIMES_KEPT = 600;
controls.onBallCam = () => { view.ballCam = !view.ballCam; markCamera(); };

// ------------------------------------------------------------------------------------------- websocket
function send(request) { if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(request)); }

function connect() {
  socket = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
  socket.binaryType = "arraybuffer";
  socket.onopen = () => { send({ op: "list" }); openFromHash(); };
  socket.onmessage = (event) => onMessage(event.data);
  socket.onclose = () => {
    $("connection").textContent = "page server gone; reconnecting…";
    setTimeout(connect, 2000);
  };
}

function onMessage(data) {
  const message = decode(new Uint8Array(data));
  const now = performance.now() / 1000;
  switch (message.type) {
    case "list": showList(message); break;
    case "watching": {
      const mine = !!seat && seat.match === message.id;
      timeline.startLive(mine);
      pendingGoal = null;
      $("timeline").hidden = mine; // a spectator may pause and rewind a live game; a player's game stays live
      setTitle(mine ? `you are ${seat.slot} in match ${message.id}`
        : `${message.kind === "train" ? "training run" : "match"} ${message.id}`);
      break;
    }
    case "roster": setRoster(message); break;
    case "status": status = message; showFinalStats(null); setTitle(); break;
    case "hint": showNotice(message.text); break;
    case "frame":
      if (noticeIsHint) showNotice(null);
      stats.frames += 1; stats.bytesLast = data.byteLength; stats.bytesMax = Math.max(stats.bytesMax, data.byteLength);
      stats.arrivals.push(now);
      frameArrivals.push([message.t, now * 1000]);
      if (frameArrivals.length > TIMES_KEPT) frameArrivals.shift();
      timeline.pushLive(message, now);
      if (!timeline.asPlayer && timeline.follow) {
        pendingGoal = (message.e || []).find((e) => e.kind === "goal") || pendingGoal;
      }
      break;
    case "final":
      if (seat) seat.ended = true;
      timeline.addEvents(message.events);
      status = { ...(status || {}), status: message.status, final: true, info: message.info || (status || {}).info };
      if (message.status === "lost" || message.status === "failed") {
        showNotice(`match ${message.status}: ${message.error}`, false);
      }
      showFinalStats(message.summary);
      setTitle();
      break;
    case "replay":
      openReplay(message);
      if (message.league) {
        showNotice(message.league.same_score === false ? "this replay's score differs from the stored result" : null,
          false);
        setTitle(`league match ${message.league.key} · played again from its seed`);
      }
      break;
    case "seat": onSeat(message); break;
    case "ack": onAck(message.n); break;
    case "error": console.warn(`page server: ${message.error}`); setTitle(`error: ${message.error}`); break;
    default: console.warn(`page server: unknown message ${message.type}`);
  }
}

// ------------------------------------------------------------------------------------------- lists
function item(text, detail, active, onClick) {
  const li = document.createElement("li");
  li.textContent = text;
  if (detail) { const small = document.createElement("small"); small.textContent = detail; li.append(small); }
  if (active) li.classList.add("active");
  li.addEventListener("click", onClick);
  return li;
}

function showList(list) {
  lastList = list;
  const z = list.zenoh;
  $("connection").textContent = z.connected ? `match server "${z.server}"`
    : (z.error ? "no match server reachable" : "replays only");
  const isActive = (kind, id) => source && source.kind === kind && source.id === id;
  const score = (s) => (s ? ` ${s.blue ?? s[0]}-${s.orange ?? s[1]}` : "");
  $("list-matches").replaceChildren(...(list.matches.length ? list.matches.map((m) => {
    const li = item(m.id, `${m.status} · ${m.mode} · ${m.config}${score(m.score)}`, isActive("match", m.id),
      () => watch("match", m.id));
    if (list.play && m.mode === "realtime" && m.status === "waiting") {
      const join = document.createElement("button");
      join.textContent = "Play"; join.className = "join";
      join.addEventListener("click", (e) => { e.stopPropagation(); play({ match: m.id }); });
      li.append(join);
    }
    return li;
  }) : [item("none", null, false, () => {})]));
  showPlayChoices(list.play);
  $("list-training").replaceChildren(...(list.training.length ? list.training.map((r) =>
    item(r.id, r.status === "unverified" ? "unverified: anyone may publish under this name" : "publishing evaluation episodes", isActive("train", r.id), () => watch("train", r.id)))
    : [item("none", null, false, () => {})]));
  $("list-replays").replaceChildren(...(list.replays.length ? list.replays.map((r) =>
    item(r.id, `${(r.bytes / 1024).toFixed(0)} kB · ${new Date(r.mtime * 1000).toLocaleString()}`,
      isActive("replay", r.id), () => openReplayById(r.id))) : [item("none", null, false, () => {})]));
}

// One line over the arena: a hint while nothing is shown yet (cleared by the first frame), or how a match was lost.
let noticeIsHint = false;
function showNotice(text, isHint = true) {
  $("notice").hidden = !text;
  $("notice").textContent = text || "";
  noticeIsHint = !!text && isHint;
}

function watch(kind, id) {
  if (seat) leaveSeat();
  showNotice(null);
  showFinalStats(null);
  source = { kind, id };
  location.hash = `${kind}=${encodeURIComponent(id)}`;
  status = null;
  $("timeline").hidden = true;
  timeline.startLive();
  send({ op: "watch", kind, id });
  if (lastList) showList(lastList);
}

function openReplayById(id) {
  if (seat) leaveSeat();
  showNotice(null);
  showFinalStats(null);
  source = { kind: "replay", id };
  location.hash = `replay=${encodeURIComponent(id)}`;
  status = null;
  setTitle(`loading replay ${id}…`);
  send({ op: "replay", id });
  if (lastList) showList(lastList);
}

// A league's stored match (the league page links here): the page server plays it again from its seed.
function openLeagueReplay(key) {
  if (seat) leaveSeat();
  showFinalStats(null);
  showNotice(`playing league match ${key} again from its seed…`, false);
  source = { kind: "league", id: key };
  status = null;
  setTitle(`loading league match ${key}…`);
  send({ op: "league_replay", key });
}

function openFromHash() {
  const m = /^#(match|train|replay|league)=(.+)$/.exec(location.hash);
  if (!m) return;
  const id = decodeURIComponent(m[2]);
  if (m[1] === "replay") openReplayById(id);
  else if (m[1] === "league") openLeagueReplay(id);
  else watch(m[1], id);
}

// ------------------------------------------------------------------------------------------- play
function showPlayChoices(play) {
  $("play-panel").hidden = !play;
  if (!play) return;
  const fill = (select, values) => {
    if (select.options.length === values.length) return; // keep the user's choice across list refreshes
    select.replaceChildren(...values.map((v) => {
      const o = document.createElement("option");
      o.value = o.textContent = v;
      return o;
    }));
  };
  fill($("play-config"), play.configs);
  fill($("play-opponent"), play.opponents);
}

function play(request) {
  setTitle(request.match ? `joining match ${request.match}…` : "creating a match…");
  send({ op: "play", ...request });
}

function onSeat(message) {
  if (!message.match) { seat = null; $("seat-panel").hidden = true; return; }
  seat = { match: message.match, slot: message.slot, ended: false };
  source = { kind: "match", id: message.match };
  history.replaceState(null, "", `#match=${encodeURIComponent(message.match)}`);
  status = null;
  $("timeline").hidden = true;
  timeline.startLive(true);
  sent = null;
  setTitle(`you are ${message.slot} in match ${message.match}`);
  $("seat-panel").hidden = false;
  showBindings();
  if (lastList) showList(lastList);
}

function leaveSeat() {
  send({ op: "leave" });
  seat = null;
  controls.releaseAll();
  $("seat-panel").hidden = true;
}

// Send the controls when they change (the server keeps applying the last ones).
// `keyAt`: the time of the key event that changed them
function sendControls(keyAt = null) {
  if (!seat || seat.ended) return;
  const c = controls.read();
  const key = c.join(",");
  if (key === sent) return;
  sent = key;
  inputSeq += 1;
  const sentAt = performance.now();
  inputSentAt.set(inputSeq, sentAt);
  send({ op: "input", c, n: inputSeq });
  inputTimes.push({ n: inputSeq, c, key: keyAt, sent: sentAt, ack: null });
  if (inputTimes.length > TIMES_KEPT) inputTimes.shift();
}

function onAck(n) {
  const at = inputSentAt.get(n);
  inputSentAt.delete(n);
  if (at === undefined) return;
  const entry = inputTimes.find((e) => e.n === n);
  if (entry) entry.ack = performance.now();
  ackMs.push(performance.now() - at);
  if (ackMs.length > 50) ackMs.shift();
  const sorted = [...ackMs].sort((a, b) => a - b);
  $("latency").textContent = `input to the page server: ${sorted[Math.floor(sorted.length / 2)].toFixed(0)} ms` +
    ` · view ${(timeline.lagS() * 1000).toFixed(0)} ms behind the newest state`;
}

function showBindings() {
  const pretty = (code) => code.replace(/^Key/, "").replace(/^Digit/, "");
  $("bindings").replaceChildren(...BINDABLE.map(([action, label]) => {
    const li = document.createElement("li");
    const b = document.createElement("button");
    b.textContent = rebinding === action ? "press a key…" : pretty(controls.keys[action]);
    b.addEventListener("click", () => { rebinding = action; showBindings(); });
    li.append(b, ` ${label}`);
    return li;
  }));
}

$("play-create").addEventListener("click",
  () => play({ config: $("play-config").value, opponent: $("play-opponent").value }));
$("seat-leave").addEventListener("click", () => { leaveSeat(); setTitle("left the match"); });
$("bindings-reset").addEventListener("click", () => { controls.resetBindings(); showBindings(); });

// ------------------------------------------------------------------------------------------- replays
function openReplay(message) {
  setRoster(message.roster);
  timeline.loadReplay(message.frames, message.frames.length ? message.frames[0].r : 120);
  status = { status: "replay", info: {} };
  setTitle(`replay ${message.id} · ${message.frames.length} states`);
  const seek = $("seek");
  seek.min = timeline.firstTick; seek.max = timeline.lastTick; seek.value = timeline.firstTick;
  showGoalMarks();
  $("timeline").hidden = false;
  $("speed").value = "1";
  timeline.speed = 1;
}

// A mark on the timeline per goal in it (a replay's, or the live buffer's).
function showGoalMarks() {
  const span = Math.max(1, timeline.lastTick - timeline.firstTick);
  $("goal-marks").replaceChildren(...timeline.events.filter((e) => e.kind === "goal" && e.tick >= timeline.firstTick)
    .map((e) => {
      const mark = document.createElement("span");
      mark.className = e.team; mark.title = describe(e)[0];
      mark.style.left = `${(100 * (e.tick - timeline.firstTick)) / span}%`;
      return mark;
    }));
}

// A live game's goal, replayed once the view is INSTANT_REPLAY_DELAY_S past it: its last seconds before the goal.
const INSTANT_REPLAY_DELAY_S = 1.5, INSTANT_REPLAY_BEFORE_S = 4, INSTANT_REPLAY_AFTER_S = 1;
let pendingGoal = null, replayedGoal = null;
function startInstantReplay() {
  if (!pendingGoal) return;
  if (!timeline.live || !timeline.follow) { pendingGoal = null; return; } // paused or rewound: the user's choice
  const rate = timeline.tickRate;
  if (timeline.playhead < pendingGoal.tick + INSTANT_REPLAY_DELAY_S * rate) return;
  replayedGoal = pendingGoal;
  pendingGoal = null;
  timeline.instantReplay(replayedGoal.tick - INSTANT_REPLAY_BEFORE_S * rate,
    replayedGoal.tick + INSTANT_REPLAY_AFTER_S * rate);
}

$("play").addEventListener("click", () => togglePlay());
$("step-back").addEventListener("click", () => timeline.step(-1));
$("step-forward").addEventListener("click", () => timeline.step(1));
$("go-live").addEventListener("click", () => timeline.goLive());
$("seek").addEventListener("input", (e) => {
  if (timeline.live) timeline.holdLive();
  timeline.playing = false;
  timeline.seek(Number(e.target.value));
});
$("speed").addEventListener("change", (e) => { timeline.speed = Number(e.target.value); });

function togglePlay() {
  if (timeline.live) {
    if (timeline.asPlayer) return;
    if (timeline.follow || timeline.replaying) { timeline.holdLive(); timeline.playing = false; }
    else timeline.playing = !timeline.playing; // on from where it was paused; the live edge takes it back
    return;
  }
  if (!timeline.playing && timeline.playhead >= timeline.lastTick) timeline.seek(timeline.firstTick);
  timeline.playing = !timeline.playing;
}

// ------------------------------------------------------------------------------------------- HUD
function setRoster(r) {
  roster = r;
  view.setRoster(r);
  const mine = seat ? r.agents.indexOf(seat.slot) : -1;
  if (mine >= 0 && !(view.cameraMode === "chase" && view.chaseIndex === mine)) view.setCamera("chase", mine);
  for (const team of [0, 1]) {
    const panel = $(team === 0 ? "boost-blue" : "boost-orange");
    panel.replaceChildren(...r.agents.map((agent, i) => {
      if (r.teams[i] !== team) return null;
      const div = document.createElement("div");
      div.className = "car-boost"; div.dataset.index = i;
      div.innerHTML = `<span class="name"></span> <b class="amount"></b>` +
        `<div class="bar"><div class="fill"></div></div>`;
      div.querySelector(".name").textContent = r.names[i] === agent ? agent : `${agent} · ${r.names[i]}`;
      if (i === mine) div.classList.add("you");
      return div;
    }).filter(Boolean));
  }
  boostPanels = [...document.querySelectorAll(".car-boost")];
  $("tags").replaceChildren(...r.agents.map((agent, i) => {
    const tag = document.createElement("div");
    tag.className = `t${r.teams[i]}${i === mine ? " you" : ""}`;
    tag.textContent = i === mine ? `${agent} (you)` : agent;
    return tag;
  }));
  written.clear();
  const cams = [["broadcast", "Broadcast"], ["top", "Top-down"], ["orbit", "Orbit"],
    ...r.agents.map((a, i) => [`chase:${i}`, `Chase ${a}`])];
  $("cameras").replaceChildren(...cams.map(([mode, label]) => {
    const b = document.createElement("button");
    b.textContent = label; b.dataset.mode = mode;
    b.addEventListener("click", () => setCamera(mode));
    return b;
  }));
  markCamera();
}

function setCamera(mode) {
  if (mode.startsWith("chase:")) view.setCamera("chase", Number(mode.slice(6))); else view.setCamera(mode);
  markCamera();
}

function markCamera() {
  const current = view.cameraMode === "chase" ? `chase:${view.chaseIndex}` : view.cameraMode;
  for (const b of $("cameras").children) b.classList.toggle("active", b.dataset.mode === current);
  $("ball-cam").textContent = seat && view.cameraMode === "chase" ? (view.ballCam ? "ball cam" : "car cam") : "";
}

function setTitle(text) {
  if (text !== undefined) { setTitle.base = text; }
  let line = setTitle.base || "";
  if (status && status.status && status.status !== "replay") line += ` · ${status.status}`;
  if (status && status.info && status.info.iteration !== undefined) line += ` · iteration ${status.info.iteration}`;
  $("title").textContent = line;
}

function clock(seconds, overtime) {
  const s = Math.max(0, overtime ? Math.floor(seconds) : Math.ceil(seconds));
  return `${overtime ? "+" : ""}${Math.floor(s / 60)}:${String(s % 60).padStart(2, "0")}`;
}

function describe(e) {
  const name = (agent) => {
    if (!roster || !agent) return agent || "nobody";
    const i = roster.agents.indexOf(agent);
    return i >= 0 && roster.names[i] !== agent ? `${agent} (${roster.names[i]})` : agent;
  };
  const team = (agent) => (agent && agent.startsWith("orange") ? "orange" : "blue");
  switch (e.kind) {
    case "goal": return [`GOAL ${e.team}: ${name(e.scorer)}${e.own_goal ? " (own goal)" : ""}`, `goal ${e.team}`];
    case "save": return [`save by ${name(e.agent)}`, team(e.agent)];
    case "demo": return [`${name(e.agent)} demolished ${name(e.victim)}`, team(e.agent)];
    case "shot": return [`shot by ${name(e.agent)}`, team(e.agent)];
    case "overtime": return ["OVERTIME", ""];
    case "miss": return [`miss (${e.reason})`, ""];
    default: return [e.kind, ""];
  }
}

// Set a text or style only when it changes: the HUD is redrawn every frame, the DOM should not be.
const written = new Map();
function write(el, key, value, apply) {
  const id = `${el.id || el.dataset.index}:${key}`;
  if (written.get(id) !== value) { written.set(id, value); apply(value); }
}

let shownFeed = "";
function updateHud(s) {
  if (!s) return;
  write($("score-blue"), "text", s.s[0], (v) => { $("score-blue").textContent = v; });
  write($("score-orange"), "text", s.s[1], (v) => { $("score-orange").textContent = v; });
  write($("clock"), "text", clock(s.c, s.o), (v) => { $("clock").textContent = v; });
  write($("overtime"), "hidden", !s.o, (v) => { $("overtime").hidden = v; });
  for (const div of boostPanels) {
    const car = s.a[Number(div.dataset.index)];
    write(div, "amount", car ? String(Math.round(car[7])) : "–",
      (v) => { div.querySelector(".amount").textContent = v; });
    write(div, "fill", car ? Math.round(car[7]) : 0, (v) => { div.querySelector(".fill").style.width = `${v}%`; });
    write(div, "demoed", !!car && (car[8] & FLAG_DEMOED) !== 0, (v) => div.classList.toggle("demoed", v));
  }
  const events = timeline.shownEvents(8);
  const key = events.map((e) => `${e.kind}${e.tick}${e.agent || e.scorer || ""}`).join("|");
  if (key !== shownFeed) {
    shownFeed = key;
    $("feed").replaceChildren(...events.map((e) => {
      const [text, cls] = describe(e);
      const li = document.createElement("li");
      li.textContent = `${e.clock === undefined ? "" : clock(e.clock, e.overtime)}  ${text}`;
      if (cls) li.className = cls;
      return li;
    }));
  }
  if (timeline.live && !$("timeline").hidden && timeline.frames.length) {
    const seek = $("seek");
    write(seek, "min", timeline.firstTick, (v) => { seek.min = v; });
    write(seek, "max", timeline.lastTick, (v) => { seek.max = v; });
    write(seek, "value", Math.round(timeline.playhead), (v) => { seek.value = v; });
    const behindS = (timeline.lastTick - timeline.playhead) / timeline.tickRate;
    const where = timeline.follow ? "live" : `${timeline.replaying ? "replay " : ""}-${behindS.toFixed(1)} s`;
    write($("time"), "text", where, (v) => { $("time").textContent = v; });
    write($("play"), "text", timeline.follow || timeline.playing ? "Pause" : "Play",
      (v) => { $("play").textContent = v; });
    write($("go-live"), "hidden", timeline.follow, (v) => { $("go-live").hidden = v; });
    const goals = timeline.events.filter((e) => e.kind === "goal" && e.tick >= timeline.firstTick).length;
    const span = `${Math.round(timeline.firstTick / 60)}|${Math.round(timeline.lastTick / 60)}`;
    write($("goal-marks"), "at", `${goals}|${span}`, showGoalMarks);
  }
  if (!timeline.live && timeline.frames.length) {
    write($("go-live"), "hidden", true, (v) => { $("go-live").hidden = v; });
    write($("seek"), "value", Math.round(timeline.playhead), (v) => { $("seek").value = v; });
    const t0 = timeline.firstTick, rate = timeline.tickRate;
    $("time").textContent = `${clock((timeline.playhead - t0) / rate, true).replace("+", "")} / ` +
      `${clock((timeline.lastTick - t0) / rate, true).replace("+", "")}`;
    $("play").textContent = timeline.playing ? "Pause" : "Play";
  }
}

// Each car's name over it, where it is drawn (hidden for a car not drawn or behind the camera).
const TAG_ABOVE_UU = 110;
function updateTags(s) {
  const tags = $("tags").children;
  for (let i = 0; i < tags.length; i++) {
    const car = s ? s.a[i] : null;
    const shownCar = car && !(car[8] & FLAG_DEMOED) && !hudHidden;
    const at = shownCar ? view.screenPoint([car[0], car[1], car[2] + TAG_ABOVE_UU]) : null;
    // written only when it changes: a style write costs the page a style pass
    const place = at ? `translate(${Math.round(at[0])}px, ${Math.round(at[1])}px) translate(-50%, -100%)` : "none";
    if (tags[i].dataset.place === place) continue;
    tags[i].dataset.place = place;
    tags[i].style.display = at ? "" : "none";
    if (at) tags[i].style.transform = place;
  }
}

// The tick the kickoff countdown now showing began at: the first of the run of frames with the cars held.
function kickoffStartTick() {
  const frames = timeline.frames;
  let i = timeline.index();
  while (i > 0 && frames[i - 1].k) i--;
  return frames.length ? frames[i].t : 0;
}

// A goal's banner for 3 s of game time after it; KICKOFF and the seconds left while the countdown holds the cars.
const BANNER_S = 3;
function updateBanner(s) {
  let text = null, cls = "", sub = "";
  const goal = s ? timeline.shownEvents(8).filter((e) => e.kind === "goal").pop() : null;
  if (s && timeline.replaying && replayedGoal) {
    text = "REPLAY"; cls = replayedGoal.team; sub = describe(replayedGoal)[0];
  } else if (goal && timeline.playhead - goal.tick < BANNER_S * (s.r || 120)) {
    text = `GOAL ${goal.team.toUpperCase()}`; cls = goal.team; sub = describe(goal)[0].replace(/^GOAL \w+: /, "");
  } else if (s && s.k) {
    text = "KICKOFF";
    if (roster && roster.countdown_s) {
      const left = roster.countdown_s - (s.t - kickoffStartTick()) / (s.r || 120);
      if (left > 0) text = `KICKOFF ${Math.ceil(left)}`;
    }
  }
  write($("banner"), "banner", `${text}|${cls}|${sub}`, () => {
    $("banner").hidden = !text;
    $("banner").className = cls;
    $("banner").textContent = text || "";
    if (sub) { const small = document.createElement("small"); small.textContent = sub; $("banner").append(small); }
  });
}

// The end of a match: each car's line of the summary the server sends (goals, shots, saves, touches, team play).
const STAT_COLUMNS = [["goals", "G"], ["shots", "Sh"], ["saves", "Sv"], ["assists", "A"], ["passes", "Pass"],
  ["demos", "Demo"], ["touches", "Touch"], ["boost_collected", "Boost"]];
function showFinalStats(summary) {
  const box = $("final-stats");
  if (!summary || !summary.stats || !roster) { box.hidden = true; return; }
  const head = document.createElement("tr");
  head.append(...["", ...STAT_COLUMNS.map(([, label]) => label)].map((t) => {
    const th = document.createElement("th");
    th.textContent = t;
    return th;
  }));
  const rows = roster.agents.filter((a) => summary.stats[a]).map((agent) => {
    const tr = document.createElement("tr");
    tr.className = `t${roster.teams[roster.agents.indexOf(agent)]}`;
    const name = roster.names[roster.agents.indexOf(agent)];
    tr.append(...[name === agent ? agent : `${agent} · ${name}`, ...STAT_COLUMNS.map(([k]) => {
      const v = summary.stats[agent][k];
      return v === undefined ? "–" : typeof v === "number" && !Number.isInteger(v) ? v.toFixed(0) : String(v);
    })].map((t) => { const td = document.createElement("td"); td.textContent = t; return td; }));
    return tr;
  });
  const title = document.createElement("h3");
  const score = summary.score
    ? `${summary.score.blue ?? summary.score[0]} – ${summary.score.orange ?? summary.score[1]}` : "";
  title.textContent = `${summary.winner ? `${summary.winner} wins` : "draw"} ${score}`;
  const table = document.createElement("table");
  table.append(head, ...rows);
  const close = document.createElement("button");
  close.textContent = "close"; close.addEventListener("click", () => { box.hidden = true; });
  box.replaceChildren(title, table, close);
  box.hidden = false;
}

// ------------------------------------------------------------------------------------------- keys
window.addEventListener("keydown", (e) => {
  if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
  if (rebinding) { controls.bind(rebinding, e.code); rebinding = null; showBindings(); e.preventDefault(); return; }
  if (seat && controls.keyDown(e.code)) { e.preventDefault(); sendControls(e.timeStamp); return; }
  if (e.key === "1") setCamera("broadcast");
  else if (e.key === "2") setCamera("top");
  else if (e.key === "4") setCamera("orbit");
  else if (e.key === "3" && roster && roster.agents.length) {
    setCamera(`chase:${view.cameraMode === "chase" ? (view.chaseIndex + 1) % roster.agents.length : view.chaseIndex}`);
  } else if (e.key === " ") { togglePlay(); e.preventDefault(); }
  else if (e.key === "ArrowRight") timeline.step(1);
  else if (e.key === "ArrowLeft") timeline.step(-1);
  else if (e.key === "l" && timeline.live) timeline.goLive();
  else if (e.key === "h") { hudHidden = !hudHidden; $("hud").classList.toggle("hidden", hudHidden); }
});

// The orbit camera: drag on the view to turn it round the ball (a drag in another camera switches to it),
// the wheel to zoom.
let dragFrom = null;
$("view").addEventListener("pointerdown", (e) => {
  dragFrom = [e.clientX, e.clientY];
  $("view").setPointerCapture(e.pointerId);
});
$("view").addEventListener("pointerup", () => { dragFrom = null; });
$("view").addEventListener("pointermove", (e) => {
  if (!dragFrom) return;
  if (view.cameraMode !== "orbit") setCamera("orbit");
  view.turnOrbit(e.clientX - dragFrom[0], e.clientY - dragFrom[1]);
  dragFrom = [e.clientX, e.clientY];
});
$("view").addEventListener("wheel", (e) => {
  if (view.cameraMode !== "orbit") return;
  view.zoomOrbit(Math.sign(e.deltaY));
  e.preventDefault();
}, { passive: false });

window.addEventListener("keyup", (e) => { controls.keyUp(e.code); if (seat) sendControls(e.timeStamp); });
window.addEventListener("blur", () => { controls.releaseAll(); if (seat) sendControls(); });

setInterval(() => send({ op: "list" }), 3000);
window.addEventListener("hashchange", () => {
  const wanted = location.hash, current = source ? `#${source.kind}=${encodeURIComponent(source.id)}` : "";
  if (wanted !== current) openFromHash();
});

// ------------------------------------------------------------------------------------------- loop
let last = performance.now() / 1000, shown = null;
// How long the page stays busy after each frame (a software compositor takes the canvas synchronously): a message
// posted as the frame is drawn runs once the page is free again; key presses and states wait as long.
const afterFrame = new MessageChannel();
let afterFrameFrom = null;
afterFrame.port1.onmessage = () => {
  stats.busyMs.push(performance.now() - afterFrameFrom);
  if (stats.busyMs.length > 120) stats.busyMs.shift();
  afterFrameFrom = null;
};
function loop() {
  const now = performance.now() / 1000;
  const dt = Math.min(now - last, 0.25);
  const started = performance.now();
  last = now;
  sendControls(); // gamepads have no events: read every frame
  startInstantReplay();
  timeline.advance(dt, now);
  shown = timeline.current();
  if (shown) view.setObstacles(shown.x);
  view.draw(shown, now, dt, shown ? timeline.trail(TRAIL_POINTS, 0.6) : []);
  updateHud(shown);
  updateTags(shown);
  updateBanner(shown);
  stats.loopMs = stats.loopMs === undefined ? 0 : 0.95 * stats.loopMs + 0.05 * (performance.now() - started);
  stats.renders.push(now);
  while (stats.renders.length && stats.renders[0] < now - 2) stats.renders.shift();
  if (afterFrameFrom === null) { afterFrameFrom = performance.now(); afterFrame.port2.postMessage(0); }
  if (!SHARP && now - (stats.adaptedAt || 0) > 2) { // every 2 s, from the frame rate of those 2 s
    stats.adaptedAt = now;
    if (stats.renders.length > 2 && now - stats.renders[0] > 1.9) view.adaptResolution(rate(stats.renders));
  }
  while (stats.arrivals.length && stats.arrivals[0] < now - 2) stats.arrivals.shift();
  requestAnimationFrame(loop);
}

function median(values) { return [...values].sort((a, b) => a - b)[Math.floor(values.length / 2)]; }

function wall(ms) { return ms === null ? null : performance.timeOrigin + ms; }

function rate(times) {
  return times.length > 1 ? (times.length - 1) / (times[times.length - 1] - times[0]) : 0;
}

// A small read-only hook for tests and debugging: what the view shows, never a way to change the game.
window.__view = {
  ready: false,
  ballPosition: () => (shown ? [...shown.b] : null),
  // each car's position, null for a car not drawn (absent or demolished)
  carPositions: () => (shown ? shown.a.map((c) => (c && !(c[8] & FLAG_DEMOED) ? c.slice(0, 3) : null)) : null),
  project: (point) => view.project(point),
  camera: () => view.cameraMode,
  cameraPosition: () => view.camera.position.toArray(),
  score: () => (shown ? [...shown.s] : null),
  hudScore: () => [Number($("score-blue").textContent), Number($("score-orange").textContent)],
  banner: () => ($("banner").hidden ? null : $("banner").textContent),
  tick: () => timeline.playhead,
  lastTick: () => timeline.lastTick,
  // live: whether the view follows the newest state, and whether it shows a goal's instant replay
  following: () => timeline.live && timeline.follow,
  replaying: () => timeline.replaying,
  frameIndex: () => timeline.index(),
  mode: () => (source ? source.kind : null),
  // each car as drawn: [x, y, z, qx, qy, qz, qw, boost, flags], null for a car not in the game
  carStates: () => (shown ? shown.a.map((c) => (c ? [...c] : null)) : null),
  seat: () => (seat ? { ...seat } : null),
  // whether the state drawn holds the cars for a kickoff countdown (no control reaches them then)
  kickoffPending: () => (shown ? !!shown.k : null),
  // the tick of the state drawn
  shownTick: () => (shown ? shown.t : null),
  // the newest state received (not yet drawn, perhaps): its car `i`, and when it arrived (performance.now, ms)
  newestCar: (i) => (timeline.frames.length ? timeline.frames[timeline.frames.length - 1].a[i] : null),
  newestArrivalMs: () => timeline.lastArrival * 1000,
  // the last inputs' round trips to the page server (ms)
  inputAcksMs: () => [...ackMs],
  // the same on the wall clock (ms since 1970, as the servers' time.time() * 1000): each input's key event,
  // send and ack, and each of the last frames' tick and arrival
  inputTimes: () => inputTimes.map((e) => ({ ...e, key: wall(e.key), sent: wall(e.sent), ack: wall(e.ack) })),
  frameArrivals: () => frameArrivals.map(([t, at]) => [t, wall(at)]),
  inputsSent: () => inputSeq,
  ballCam: () => view.ballCam,
  roster: () => roster,
  stats: () => ({ fps: rate(stats.renders), statesPerS: rate(stats.arrivals), frames: stats.frames,
    bytesLast: stats.bytesLast, bytesMax: stats.bytesMax, loopMs: stats.loopMs,
    busyAfterFrameMs: stats.busyMs.length ? median(stats.busyMs) : null,
    pixelRatio: view.renderer.getPixelRatio() }),
};

fetch("/arena.json").then((r) => r.json()).then((arena) => {
  view.setArena(arena);
  window.__view.ready = true;
  connect();
  requestAnimationFrame(loop);
});

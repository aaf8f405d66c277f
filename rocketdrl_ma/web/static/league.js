// The league page: standings, ratings with their interval, payoff matrix and matches, from /api/league.
const $ = (id) => document.getElementById(id);

function cell(tag, text, cls) {
  const el = document.createElement(tag);
  if (text instanceof Node) el.append(text); else el.textContent = text;
  if (cls) el.className = cls;
  return el;
}

function table(id, head, rows) {
  const tr = (cells, tag) => {
    const row = document.createElement("tr");
    row.append(...cells.map((c) => (c instanceof Node && c.tagName === tag.toUpperCase() ? c : cell(tag, c))));
    return row;
  };
  $(id).replaceChildren(tr(head, "th"), ...rows.map((r) => tr(r, "td")));
}

// A rating's interval [low, high] as a bar on the axis all ratings share, its mean marked.
function intervalBar(r, lo, hi) {
  const box = cell("div", "", "interval");
  const at = (v) => `${(100 * (v - lo)) / Math.max(1e-9, hi - lo)}%`;
  const bar = cell("span", "", "range");
  bar.style.left = at(r.low);
  bar.style.width = `calc(${at(r.high)} - ${at(r.low)})`;
  const mean = cell("span", "", "mean");
  mean.style.left = at(r.mu);
  box.append(bar, mean);
  box.title = `${r.low.toFixed(1)} to ${r.high.toFixed(1)}`;
  return box;
}

function show(league) {
  document.title = `rocketdrl-ma: league ${league.name}`;
  $("league-title").textContent = `League ${league.name}`;
  $("league-about").textContent = `${league.played} of ${league.scheduled} scheduled matches played on ` +
    `${league.match} · config ${league.config} · results ${league.results}`;
  table("standings", ["#", "entrant", "matches", "W", "D", "L", "goals", "points"],
    league.standings.map((s, i) => [String(i + 1), s.name, String(s.matches), String(s.wins), String(s.draws),
      String(s.losses), `${s.goals_for}:${s.goals_against}`, s.points.toFixed(1)]));
  const k = league.interval_sigmas;
  $("ratings-about").textContent = `openskill (Plackett-Luce), rated in schedule order: mean μ and its interval ` +
    `μ ± ${k}σ; ranked by the interval's low end (the ordinal).`;
  const lo = Math.min(...league.ratings.map((r) => r.low)), hi = Math.max(...league.ratings.map((r) => r.high));
  table("ratings", ["#", "player", "μ", "σ", `μ − ${k}σ`, `μ + ${k}σ`, "interval", "matches"],
    league.ratings.map((r, i) => [String(i + 1), r.name, r.mu.toFixed(2), r.sigma.toFixed(2), r.low.toFixed(2),
      r.high.toFixed(2), cell("td", intervalBar(r, lo, hi)), String(r.matches)]));
  table("payoff", ["", ...league.entrants], league.payoff.map((row, i) => [league.entrants[i],
    ...row.map((c) => (c === null ? "–" : `${c.points.toFixed(2)} (${c.games})`))]));
  table("matches", ["match", "blue", "score", "orange", "seed", "replay"], league.matches.map((m) => {
    let replay = "played on a server";
    if (m.replay) {
      replay = cell("a", "replay");
      replay.href = `/#league=${encodeURIComponent(m.key)}`;
    }
    return [m.key, m.blue, `${m.score[0]} – ${m.score[1]}`, m.orange, String(m.seed), cell("td", replay)];
  }));
}

fetch("/api/league").then(async (r) => {
  if (!r.ok) throw new Error(await r.text());
  return r.json();
}).then(show).catch((e) => { $("league-about").textContent = String(e.message || e); });

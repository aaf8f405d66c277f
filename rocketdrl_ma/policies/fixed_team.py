"""One team's view of a game whose other team is played by fixed policies: a PettingZoo ParallelEnv.

``FixedTeamEnv(rocketdrl_ma.parallel_env("matches/2v2.yaml"), team="orange", policy="scripted:ball_chaser")``
has only the blue agents; each decision the orange cars act on the ``Policy`` interface (one policy instance per
car, reset at every episode), so a trainer that learns every agent it sees (BenchMARL, SuperSuit + SB3) trains one
team against a fixed opponent.
"""
from __future__ import annotations

from gymnasium import spaces
from pettingzoo import ParallelEnv

from rocketdrl_ma.engine import float32_controls
from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.validation import check_choice

from .registry import load_policy

TEAMS = ("blue", "orange")


class FixedTeamEnv(ParallelEnv):
    """``env`` without ``team``'s agents, whom ``policy`` (a ``load_policy`` spec) drives inside ``step``."""

    def __init__(self, env: RocketDRLParallelEnv, team: str, policy: str):
        check_choice("team", team, TEAMS)
        self.env = env
        self.fixed_agents = [agent for agent in env.possible_agents if agent.startswith(f"{team}_")]
        if not self.fixed_agents:
            raise ValueError(f"team: this game has no {team} cars (agents: {env.possible_agents})")
        if len(self.fixed_agents) == len(env.possible_agents):
            raise ValueError(f"team: every car of this game is {team}; nobody would be left to learn")
        self.policies = {agent: load_policy(policy) for agent in self.fixed_agents}
        self.possible_agents = [agent for agent in env.possible_agents if agent not in self.fixed_agents]
        self.agents: list[str] = []
        self.metadata = env.metadata
        self.render_mode = env.render_mode
        self.state_space = env.state_space

    def observation_space(self, agent: str) -> spaces.Space:
        return self.env.observation_space(agent)

    def action_space(self, agent: str) -> spaces.Space:
        return self.env.action_space(agent)

    def _learners(self, per_agent: dict) -> dict:
        return {agent: value for agent, value in per_agent.items() if agent not in self.policies}

    def reset(self, seed: int | None = None, options: dict | None = None):
        observations, infos = self.env.reset(seed=seed, options=options)
        for policy in self.policies.values():
            policy.reset(self.env.game_state)
        self.agents = [agent for agent in self.env.agents if agent not in self.policies]
        return self._learners(observations), self._learners(infos)

    def step(self, actions: dict):
        driven = [agent for agent in actions if agent in self.policies]
        if driven:
            raise ValueError(f"actions: {driven} are played by the fixed policies; act only for {self.possible_agents}")
        state = self.env.game_state
        fixed = float32_controls({agent: self.policies[agent].controls(agent, state) for agent in self.env.agents
                                  if agent in self.policies})
        results = self.env.play(fixed, actions)
        self.agents = [agent for agent in self.env.agents if agent not in self.policies]
        return tuple(self._learners(per_agent) for per_agent in results)

    def state(self):
        return self.env.state()

    def render(self):
        return self.env.render()

    def close(self) -> None:
        self.env.close()

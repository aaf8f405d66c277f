"""The PettingZoo face: observation builders, action parsers, the ParallelEnv, rendering and replays."""

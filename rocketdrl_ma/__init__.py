"""rocketdrl-ma: multi-agent car football on PyBullet for reinforcement learning."""

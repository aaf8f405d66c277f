"""Watch in the browser: ``rocketdrl-ma web`` serves a three.js page that shows the match server's live
matches, replay files and training runs (``bridge.py``: page files and websocket; ``feed.py``: the one
module that reads Zenoh; ``frames.py``: what the page receives; ``arena.py``: the physics' arena mesh;
``replays.py``: replay files; ``training.py``: evaluation episodes published while training)."""

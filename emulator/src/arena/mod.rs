//! Arenas from files: CiberRato lab XML, micromouse maze text, ROS map_server PGM+YAML, ASCII grid.

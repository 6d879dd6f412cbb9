"""Controllers (flight side): pure functions of measured/received signals and controller states."""

"""Running one experiment: seeding, the env-step loop, the logger façade, the run summary."""

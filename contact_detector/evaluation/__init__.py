"""Event metrics and baseline detectors, shared by evaluate, train and the sweep."""

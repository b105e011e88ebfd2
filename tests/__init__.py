"""pincal tests: one folder per subpackage, plus the studies and the README."""

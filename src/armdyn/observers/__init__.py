"""Observers of an arm's external torques: residuals that sense contact without a force sensor, thresholds
on them, and the detection of collisions (De Luca and Mattone 2003; Haddadin, De Luca and Albu-Schaeffer
2017)."""

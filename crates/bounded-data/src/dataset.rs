//! Labelled datasets: directories or generated sets with train / validation / evaluation roles.

//! Writing results: numbered PNG frames and GIF animations.
